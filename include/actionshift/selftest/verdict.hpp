#pragma once
/// \file The self-test's verdict (`decide_verdict`; docs/reference.md, *Self-test*), as a pure function of the
/// identification evidence, plus its text and JSON renderings.
///
/// Rules, in order (floor = confidence floor, ratio = misspecification ratio):
/// 1. fit_ratio > ratio: INCONCLUSIVE (the best hypothesis explains the responses badly: the
///    wiring is likely outside the declared pool). Every checked field is unresolved; no diffs.
/// 2. unresolved = checked fields with confidence < floor; diffs = checked fields whose identified
///    value differs from the expected one; confident diffs = diffs with confidence >= floor.
/// 3. any confident diff: MISMATCH, the reason is the diff sentences joined by "; ".
/// 4. else any unresolved field: INCONCLUSIVE (abstain rather than guess).
/// 5. else PASS.
/// Fields that cannot be checked in this run (gripper polarity without a gripper probe; scale under
/// absolute targets; tool frame under identity rotation) never enter the verdict and are listed
/// with their reason.

#include "actionshift/core/contract.hpp"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::selftest {

enum class Status {
  kPass,          ///< every checked field resolved and equal to the expected contract (exit 0)
  kMismatch,      ///< a confidently resolved field differs from the expected contract (exit 1)
  kInconclusive,  ///< abstain: the belief did not concentrate, or the pool does not explain the data (exit 2)
};
/// "PASS", "MISMATCH" or "INCONCLUSIVE".
const char* to_string(Status s);
/// 0, 1 or 2.
int exit_code(Status s);

/// The six pose-contract fields the probe identifies (gripper_inverted is never probed).
enum class Field { kPermutation, kSign, kScale, kTarget, kFrame, kLag };
inline constexpr int kNumFields = 6;
/// "permutation", "sign", "scale", "target", "frame", "lag".
const char* to_string(Field f);
/// All six, in that order.
std::array<Field, kNumFields> all_fields();
/// Python-style value of a field: "(0, 1, 2, 3, 4, 5)", "(1.0, 0.5, …)", "delta", "2".
std::string field_value(const Contract& c, Field f);
/// The reference's diff sentence for one field (empty if equal), e.g. "channels 0 and 1 SWAPPED",
/// "channel 3 sign FLIPPED", "channel 0 scale 1->0.5; channel 2 scale 1->2".
std::string diff_sentence(const Contract& expected, const Contract& wired, Field f);

/// What identification produced; the input of decide_verdict().
struct Evidence {
  Contract expected;                           ///< the wiring the policy assumes
  Contract identified;                         ///< MAP over the declared pool
  std::array<double, kNumFields> confidence{};  ///< posterior mass of pool members agreeing with the MAP on each field
  std::array<bool, kNumFields> checkable{true, true, true, true, true, true};  ///< false: not observable in this run
  std::array<std::string, kNumFields> unchecked_reason{};  ///< why, for non-checkable fields
  double fit_ratio{0.0};       ///< mean squared standardized residual of the MAP replay (≈ 1 if the model holds)
  double map_posterior{0.0};   ///< posterior probability of the MAP hypothesis
};

/// One field that the run cannot verify, and why.
struct Unchecked {
  std::string field;   ///< "gripper_inverted", "scale" or "frame"
  std::string reason;  ///< one sentence
};

/// Finger travel [units of the caller's positions] up to which held fingers count as not moved.
inline constexpr double kFingerHoldTolerance = 1e-3;

/// The verdict and everything the report shows.
struct Verdict {
  Status status{Status::kInconclusive};
  std::string reason{"self-test not run"};
  Evidence evidence;
  std::vector<std::string> unresolved_fields;  ///< checked fields below the confidence floor
  std::vector<std::string> diff_fields;        ///< confidently resolved fields that differ
  std::vector<std::string> field_diffs;        ///< their diff sentences
  std::vector<Unchecked> unchecked;            ///< always includes gripper_inverted
  double confidence_floor{0.9};
  double misspec_ratio{4.0};

  // probe accounting and the safety statement
  int probe_steps{0};                ///< probes sent and observed
  double amplitude{0.5};             ///< |raw| bound on every pose channel
  double displacement{0.0};          ///< TCP path length over the probe steps (units of the caller's positions)
  double max_excursion{0.0};         ///< largest TCP distance from the start position
  double rotation{0.0};              ///< summed |rotation| over the probe steps [rad]
  double finger_travel{-1.0};        ///< summed |finger motion| if finger positions were given, else −1
  /// The raw gripper command every probe carried, if the gripper was held (Options::gripper with
  /// finger positions at begin()); unset: the gripper channel was 0.
  std::optional<double> gripper_hold;

  int exit_code() const { return selftest::exit_code(status); }
  /// "Probe safety: bounded raw pulses only, |action| <= 0.5 per pose channel, gripper never actuated. …"
  std::string safety_statement(const std::string& unit) const;
};

/// Applies the rules above. `confidence_floor` in (0, 1], `misspec_ratio` > 0 (not re-checked here;
/// SelfTest validates its options).
Verdict decide_verdict(const Evidence& e, double confidence_floor, double misspec_ratio);

/// Context printed in the report header.
struct ReportHeader {
  std::string task{"custom"};        ///< task or robot name
  std::string backend{"embedded"};   ///< e.g. "synthetic stand-in", "Bullet simulator"
  std::string unit{"m"};             ///< unit of TCP positions
  std::string strategy{"entropy"};   ///< probe strategy
  int budget{0};                     ///< probe budget
  int pool_size{0};                  ///< declared pool size
};

/// The human report (the reference implementation's text layout).
std::string to_text(const Verdict& v, const ReportHeader& h);
/// The machine report: one JSON object, indent 2, sorted keys (the reference implementation's keys plus ours).
std::string to_json(const Verdict& v, const ReportHeader& h);

}  // namespace actionshift::selftest
