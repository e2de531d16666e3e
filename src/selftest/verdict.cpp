#include "actionshift/selftest/verdict.hpp"

#include "actionshift/core/canonical_json.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string_view>
#include <utility>

namespace actionshift::selftest {

const char* to_string(Status s) {
  switch (s) {
    case Status::kPass: return "PASS";
    case Status::kMismatch: return "MISMATCH";
    default: return "INCONCLUSIVE";
  }
}

int exit_code(Status s) {
  switch (s) {
    case Status::kPass: return 0;
    case Status::kMismatch: return 1;
    default: return 2;
  }
}

const char* to_string(Field f) {
  switch (f) {
    case Field::kPermutation: return "permutation";
    case Field::kSign: return "sign";
    case Field::kScale: return "scale";
    case Field::kTarget: return "target";
    case Field::kFrame: return "frame";
    default: return "lag";
  }
}

std::array<Field, kNumFields> all_fields() {
  return {Field::kPermutation, Field::kSign, Field::kScale, Field::kTarget, Field::kFrame, Field::kLag};
}

namespace {

std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

// `a` and `b` printed with the fewest decimals (at least `min_decimals`, at most 9) that keep them
// apart, so a printed comparison never contradicts itself ("0.90 < floor 0.90" becomes
// "0.8996 < floor 0.9000"); equal values print with `min_decimals`.
std::pair<std::string, std::string> distinct(double a, double b, int min_decimals) {
  char fa[64], fb[64];
  for (int d = min_decimals; d <= 9; ++d) {
    std::snprintf(fa, sizeof fa, "%.*f", d, a);
    std::snprintf(fb, sizeof fb, "%.*f", d, b);
    if (a == b || std::string_view(fa) != std::string_view(fb)) break;
  }
  return {fa, fb};
}

template <class T>
std::string tuple(const std::array<T, kPoseDim>& v) {
  std::string s = "(";
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i) s += ", ";
    if constexpr (std::is_floating_point_v<T>) s += python_float_repr(v[i]);
    else s += std::to_string(v[i]);
  }
  return s + ")";
}

std::string list(const std::vector<int>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

std::string quoted_list(const std::vector<std::string>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", '" : "'") + v[i] + "'";
  return s + "]";
}

}  // namespace

std::string field_value(const Contract& c, Field f) {
  switch (f) {
    case Field::kPermutation: return tuple(c.permutation());
    case Field::kSign: return tuple(c.sign());
    case Field::kScale: return tuple(c.scale());
    case Field::kTarget: return to_string(c.target());
    case Field::kFrame: return to_string(c.frame());
    default: return std::to_string(c.lag());
  }
}

std::string diff_sentence(const Contract& e, const Contract& w, Field f) {
  switch (f) {
    case Field::kPermutation: {
      std::vector<int> at;
      for (int i = 0; i < kPoseDim; ++i)
        if (e.permutation()[static_cast<std::size_t>(i)] != w.permutation()[static_cast<std::size_t>(i)]) at.push_back(i);
      if (at.empty()) return {};
      const auto a = static_cast<std::size_t>(at.size() == 2 ? at[0] : 0);
      const auto b = static_cast<std::size_t>(at.size() == 2 ? at[1] : 0);
      if (at.size() == 2 && e.permutation()[a] == w.permutation()[b] && e.permutation()[b] == w.permutation()[a])
        return "channels " + std::to_string(at[0]) + " and " + std::to_string(at[1]) + " SWAPPED";
      return "channel routing changed at channels " + list(at) + ": expected permutation " + tuple(e.permutation()) +
             ", wired " + tuple(w.permutation());
    }
    case Field::kSign: {
      std::vector<int> at;
      for (int i = 0; i < kPoseDim; ++i)
        if (e.sign()[static_cast<std::size_t>(i)] != w.sign()[static_cast<std::size_t>(i)]) at.push_back(i);
      if (at.empty()) return {};
      if (at.size() == 1) return "channel " + std::to_string(at[0]) + " sign FLIPPED";
      return "channels " + list(at) + " sign FLIPPED";
    }
    case Field::kScale: {
      std::vector<std::string> parts;
      for (int i = 0; i < kPoseDim; ++i) {
        const auto k = static_cast<std::size_t>(i);
        if (e.scale()[k] != w.scale()[k])
          parts.push_back("channel " + std::to_string(i) + " scale " + fmt("%g", e.scale()[k]) + "->" + fmt("%g", w.scale()[k]));
      }
      return join(parts, "; ");
    }
    case Field::kTarget:
      if (e.target() == w.target()) return {};
      return std::string("target encoding differs: expected ") + to_string(e.target()) + ", wired " + to_string(w.target());
    case Field::kFrame:
      if (e.frame() == w.frame()) return {};
      return std::string("reference frame differs: expected ") + to_string(e.frame()) + ", wired " + to_string(w.frame());
    default:
      if (e.lag() == w.lag()) return {};
      return "actuation lag differs: expected " + std::to_string(e.lag()) + " step(s), wired " + std::to_string(w.lag()) +
             " step(s)";
  }
}

std::string Verdict::safety_statement(const std::string& unit) const {
  const std::string gripper = gripper_hold ? "gripper held at its start position (raw gripper command " +
                                                 fmt("%+.3f", *gripper_hold) + " under the expected wiring's polarity)"
                                           : "gripper never actuated";
  std::string s = "Probe safety: bounded raw pulses only, |action| <= " + fmt("%g", amplitude) +
                  " per pose channel, " + gripper + ". Estimated end-effector displacement during probing: " +
                  fmt("%.4f", displacement) + " " + unit + " path over " + std::to_string(probe_steps) +
                  " probe steps (largest distance from the start " + fmt("%.4f", max_excursion) + " " + unit +
                  ", rotation " + fmt("%.4f", rotation) + " rad).";
  if (finger_travel >= 0 && gripper_hold)
    s += " Finger travel while probing: " + fmt("%.4f", finger_travel) + " " + unit +
         (finger_travel > kFingerHoldTolerance
              ? " (the fingers moved: a wiring with another gripper polarity, or the zeros an actuation lag sends "
                "before the first command arrives, drive them away from the held position)."
              : " (held).");
  else if (finger_travel >= 0)
    s += " Finger travel while probing: " + fmt("%.4f", finger_travel) + " " + unit +
         " (the gripper channel is 0, which a controller may map to a mid finger target).";
  return s;
}

Verdict decide_verdict(const Evidence& e, double floor, double ratio) {
  Verdict v;
  v.evidence = e;
  v.confidence_floor = floor;
  v.misspec_ratio = ratio;
  v.unchecked.push_back({"gripper_inverted", "gripper polarity is not checked without a gripper probe (the gripper is "
                                             "held or left at 0 while probing, never pulsed)"});
  std::vector<Field> checked;
  for (Field f : all_fields()) {
    const auto k = static_cast<std::size_t>(f);
    if (e.checkable[k]) checked.push_back(f);
    else v.unchecked.push_back({to_string(f), e.unchecked_reason[k]});
  }

  // 1. misspecification: the pool does not explain the responses
  if (e.fit_ratio > ratio) {
    v.status = Status::kInconclusive;
    for (Field f : checked) v.unresolved_fields.emplace_back(to_string(f));
    const auto [fit, threshold] = distinct(e.fit_ratio, ratio, 1);
    v.reason = "response misspecification: the best hypothesis fits the probe responses at " + fit +
               "x the calibrated noise scale (threshold " + threshold +
               "x) -- the true wiring is likely outside the declared pool. Abstaining.";
    return v;
  }

  // 2. unresolved fields and confident diffs
  double weakest = 1.0;
  for (Field f : checked) {
    const double c = e.confidence[static_cast<std::size_t>(f)];
    if (c < floor) {
      v.unresolved_fields.emplace_back(to_string(f));
      weakest = std::min(weakest, c);
    } else if (const std::string d = diff_sentence(e.expected, e.identified, f); !d.empty()) {
      v.diff_fields.emplace_back(to_string(f));
      v.field_diffs.push_back(d);
    }
  }

  // 3. mismatch, 4. abstain, 5. pass
  if (!v.field_diffs.empty()) {
    v.status = Status::kMismatch;
    v.reason = join(v.field_diffs, "; ");
    if (!v.unresolved_fields.empty())
      v.reason += " (note: field(s) " + quoted_list(v.unresolved_fields) +
                  " were not resolved and are not part of this verdict)";
  } else if (!v.unresolved_fields.empty()) {
    v.status = Status::kInconclusive;
    const auto [low, bar] = distinct(weakest, floor, 2);
    v.reason = "insufficient posterior mass to resolve field(s) " + quoted_list(v.unresolved_fields) + " (weakest " + low +
               " < floor " + bar + "). Abstaining rather than guessing.";
  } else {
    v.status = Status::kPass;
    v.reason = "every observable field resolved with high confidence and matches the expected wiring";
  }
  return v;
}

std::string to_text(const Verdict& v, const ReportHeader& h) {
  std::ostringstream o;
  char line[512];
  o << "ActionShift plug-and-verify self-test\n"
    << "=====================================\n"
    << "Task:           " << h.task << " (" << h.backend << ")\n"
    << "Probe strategy: " << h.strategy << "   budget " << h.budget << " steps   amplitude " << fmt("%g", v.amplitude)
    << "\n"
    << "Declared pool:  " << h.pool_size << " candidate wirings\n\n"
    << v.safety_statement(h.unit) << "\n\n"
    << "Identified wiring (MAP over the declared pool):\n";
  for (Field f : all_fields()) {
    const auto k = static_cast<std::size_t>(f);
    const std::string value = field_value(v.evidence.identified, f);
    if (v.evidence.checkable[k])
      std::snprintf(line, sizeof line, "  %-12s %-32s confidence %.2f\n", to_string(f), value.c_str(), v.evidence.confidence[k]);
    else
      std::snprintf(line, sizeof line, "  %-12s %-32s not checked\n", to_string(f), value.c_str());
    o << line;
  }
  o << "  gripper_inverted not checked (out of scope for a pose probe)\n";
  {
    const auto [fit, threshold] = distinct(v.evidence.fit_ratio, v.misspec_ratio, 2);
    o << "  fit residual: " << fit << "x calibrated noise scale ("
      << (v.evidence.fit_ratio > v.misspec_ratio ? "TOO LARGE, > " : "ok, <= ") << threshold << "x)\n";
  }
  o << "\nCannot be checked in this run:\n";
  for (const auto& u : v.unchecked) o << "  " << u.field << ": " << u.reason << "\n";
  o << "\nVERDICT: " << to_string(v.status) << "  (exit " << v.exit_code() << ")\n  " << v.reason << "\n";
  return o.str();
}

std::string to_json(const Verdict& v, const ReportHeader& h) {
  nlohmann::json j;
  j["status"] = to_string(v.status);
  j["exit_code"] = v.exit_code();
  j["reason"] = v.reason;
  j["task"] = h.task;
  j["backend"] = h.backend;
  j["strategy"] = h.strategy;
  j["budget"] = h.budget;
  j["pool_size"] = h.pool_size;
  j["amplitude"] = v.amplitude;
  j["confidence_floor"] = v.confidence_floor;
  j["misspec_ratio"] = v.misspec_ratio;
  j["identified_contract"] = v.evidence.identified.to_json_value();
  j["expected_contract"] = v.evidence.expected.to_json_value();
  nlohmann::json conf = nlohmann::json::object();
  for (Field f : all_fields()) conf[to_string(f)] = v.evidence.confidence[static_cast<std::size_t>(f)];
  j["field_confidence"] = conf;
  j["unchecked_fields"] = nlohmann::json::array();
  nlohmann::json why = nlohmann::json::object();
  for (const auto& u : v.unchecked) {
    j["unchecked_fields"].push_back(u.field);
    why[u.field] = u.reason;
  }
  j["unchecked_reasons"] = why;
  j["unresolved_fields"] = v.unresolved_fields;
  j["diff_fields"] = v.diff_fields;
  j["field_diffs"] = v.field_diffs;
  j["fit_ratio"] = v.evidence.fit_ratio;
  j["map_posterior"] = v.evidence.map_posterior;
  j["probe_steps"] = v.probe_steps;
  j["probe_displacement"] = v.displacement;
  j["probe_max_excursion"] = v.max_excursion;
  j["probe_rotation_rad"] = v.rotation;
  j["displacement_unit"] = h.unit;
  if (v.finger_travel >= 0) j["finger_travel"] = v.finger_travel;
  if (v.gripper_hold) j["gripper_hold"] = *v.gripper_hold;
  j["safety_statement"] = v.safety_statement(h.unit);
  return j.dump(2);
}

}  // namespace actionshift::selftest
