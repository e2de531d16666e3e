#pragma once
/// \file
/// Named vocabularies, each defined once: an enum and its names, with one print (`name`) and one
/// parse (`parse`, a one-line actionshift::InputError naming the source, the field and the valid
/// names) used by the CLI, experiment YAML, JSON records and files, and Python. The core ones live
/// here (rotation mode, simulator profile); the others beside their enums, built the same way:
/// sim::SafetyFlag (sim/env.hpp), eval::ProgressMode (eval/runner.hpp), eval::Verdict (eval/gates.hpp),
/// selftest::Status (selftest/verdict.hpp).

#include "actionshift/core/error.hpp"

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace actionshift {

/// One enum's names: `what` names the vocabulary in messages ("rotation mode").
template <class E, std::size_t N>
struct Vocabulary {
  struct Entry {
    E value;
    std::string_view name;
  };
  std::string_view what;
  std::array<Entry, N> entries;

  /// The name of `v` ("" for a value outside the vocabulary).
  constexpr std::string_view name(E v) const {
    for (const Entry& e : entries)
      if (e.value == v) return e.name;
    return {};
  }
  /// The value named `text`, or nothing.
  constexpr std::optional<E> find(std::string_view text) const {
    for (const Entry& e : entries)
      if (e.name == text) return e.value;
    return std::nullopt;
  }
  /// The names, in order, joined by `sep`.
  std::string list(std::string_view sep = ", ") const {
    std::string out;
    for (const Entry& e : entries) {
      if (!out.empty()) out += sep;
      out += e.name;
    }
    return out;
  }
  /// The value named `text`; otherwise throws InputError(source, field, "unknown <what> '<text>' (valid: ...)").
  E parse(std::string_view text, const std::string& source, const std::string& field) const {
    if (const auto v = find(text)) return *v;
    throw InputError(source, field,
                     "unknown " + std::string(what) + " " + quote_input(text) + " (valid: " + list() + ")");
  }
};

template <class E, class... Entries>
constexpr auto make_vocabulary(std::string_view what, Entries... entries) {
  return Vocabulary<E, sizeof...(Entries)>{what, {{entries...}}};
}

/// Which rotation decodes a contract's `tool` frame (docs/semantics.md §4).
enum class RotationMode {
  kLive,      ///< "live": the TCP orientation in the robot base frame, read before the step (default)
  kIdentity,  ///< "identity": R = I, `tool` equals `base` (the reference's headline setting)
};
inline constexpr auto kRotationModes = make_vocabulary<RotationMode>(
    "rotation mode", Vocabulary<RotationMode, 2>::Entry{RotationMode::kLive, "live"},
    Vocabulary<RotationMode, 2>::Entry{RotationMode::kIdentity, "identity"});
inline std::string_view rotation_mode_name(RotationMode m) { return kRotationModes.name(m); }
inline RotationMode parse_rotation_mode(std::string_view text, const std::string& source = "",
                                        const std::string& field = "rotation_mode") {
  return kRotationModes.parse(text, source, field);
}

/// The simulator's fidelity profile (docs/sim.md §0): part of every job id and record.
enum class Profile {
  kManiskill,  ///< "maniskill" (default): ManiSkill's one-step IK and implicit PD drives
  kIdeal,      ///< "ideal": converged IK, first-order servo
};
inline constexpr auto kProfiles = make_vocabulary<Profile>(
    "fidelity profile", Vocabulary<Profile, 2>::Entry{Profile::kManiskill, "maniskill"},
    Vocabulary<Profile, 2>::Entry{Profile::kIdeal, "ideal"});
inline std::string_view profile_name(Profile p) { return kProfiles.name(p); }
inline Profile parse_profile(std::string_view text, const std::string& source = "", const std::string& field = "profile") {
  return kProfiles.parse(text, source, field);
}

/// Every verdict word a gate writes into a verdict file (docs/formats.md §8): Gate 1 cells, Gate 0
/// decisions, promotion decisions.
enum class Verdict {
  kPass,         ///< "pass": a gated cell met its rule (Gate 1; Gate 0's competence and parity)
  kFail,         ///< "fail"
  kDescriptive,  ///< "descriptive": a cell that is reported, not gated
  kIncomplete,   ///< "incomplete": a gated cell missing a method's records
  kAdvance,      ///< "advance": Gate 0, the backbone may be used
  kExclude,      ///< "exclude": Gate 0, it may not
  kPromote,      ///< "promote": the candidate beats its matched baseline
  kExtendSeeds,  ///< "extend_seeds": fewer than three matched seeds
  kPrune,        ///< "prune": a one-seed result under the prune floor
  kReject,       ///< "reject"
};
inline constexpr auto kVerdicts = make_vocabulary<Verdict>(
    "verdict", Vocabulary<Verdict, 10>::Entry{Verdict::kPass, "pass"}, Vocabulary<Verdict, 10>::Entry{Verdict::kFail, "fail"},
    Vocabulary<Verdict, 10>::Entry{Verdict::kDescriptive, "descriptive"},
    Vocabulary<Verdict, 10>::Entry{Verdict::kIncomplete, "incomplete"},
    Vocabulary<Verdict, 10>::Entry{Verdict::kAdvance, "advance"}, Vocabulary<Verdict, 10>::Entry{Verdict::kExclude, "exclude"},
    Vocabulary<Verdict, 10>::Entry{Verdict::kPromote, "promote"},
    Vocabulary<Verdict, 10>::Entry{Verdict::kExtendSeeds, "extend_seeds"},
    Vocabulary<Verdict, 10>::Entry{Verdict::kPrune, "prune"}, Vocabulary<Verdict, 10>::Entry{Verdict::kReject, "reject"});
inline std::string verdict_name(Verdict v) { return std::string(kVerdicts.name(v)); }
inline Verdict parse_verdict(std::string_view text, const std::string& source = "", const std::string& field = "verdict") {
  return kVerdicts.parse(text, source, field);
}
/// A positive verdict: one whose loss is a regression (`gate check`).
inline constexpr bool is_positive(Verdict v) { return v == Verdict::kPass || v == Verdict::kAdvance || v == Verdict::kPromote; }

}  // namespace actionshift
