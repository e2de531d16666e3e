// Audit a log (docs/audit.md): the identification core and its reports.
#include "actionshift/selftest/audit.hpp"

#include "actionshift/adapt/grammar_belief.hpp"
#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/grammar.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <sstream>

namespace actionshift::selftest {

// ---- names

const char* to_string(RotationRep r) {
  switch (r) {
    case RotationRep::kEulerXyz: return "euler_xyz";
    case RotationRep::kEulerZyx: return "euler_zyx";
    default: return "axis_angle";
  }
}

std::string describe(RotationRep r) {
  switch (r) {
    case RotationRep::kEulerXyz: return "XYZ Euler angles (R = Rx*Ry*Rz)";
    case RotationRep::kEulerZyx: return "ZYX Euler angles (R = Rz*Ry*Rx)";
    default: return "axis-angle (rotation vector)";
  }
}

std::optional<RotationRep> parse_rotation_rep(std::string_view s) {
  if (s == "axis_angle" || s == "axis-angle" || s == "rotvec") return RotationRep::kAxisAngle;
  if (s == "euler_xyz" || s == "euler-xyz" || s == "XYZ") return RotationRep::kEulerXyz;
  if (s == "euler_zyx" || s == "euler-zyx" || s == "ZYX" || s == "sxyz") return RotationRep::kEulerZyx;
  return std::nullopt;
}

const char* to_string(GripperRange g) { return g == GripperRange::kUnit ? "[0, 1]" : "[-1, 1]"; }

std::optional<GripperRange> parse_gripper_range(std::string_view s) {
  if (s == "[-1, 1]" || s == "-1..1" || s == "symmetric" || s == "[-1,1]") return GripperRange::kSymmetric;
  if (s == "[0, 1]" || s == "0..1" || s == "unit" || s == "[0,1]") return GripperRange::kUnit;
  return std::nullopt;
}

const char* to_string(ActionKind a) {
  switch (a) {
    case ActionKind::kNextState: return "next_state";
    case ActionKind::kCurrentState: return "current_state";
    default: return "command";
  }
}

std::optional<ActionKind> parse_action_kind(std::string_view s) {
  if (s == "command") return ActionKind::kCommand;
  if (s == "next_state") return ActionKind::kNextState;
  if (s == "current_state") return ActionKind::kCurrentState;
  return std::nullopt;
}

namespace {

std::string action_words(ActionKind a) {
  switch (a) {
    case ActionKind::kNextState: return "the next logged pose (action is the next state)";
    case ActionKind::kCurrentState: return "the current logged pose (off by one: the pose at t, not t + 1)";
    default: return "a command (delta or absolute target in normalised units)";
  }
}

const char* kChannel[kPoseDim] = {"x", "y", "z", "rx", "ry", "rz"};

std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

std::string channel_list(const std::vector<int>& v) {
  std::vector<std::string> s;
  for (int c : v) s.push_back(std::to_string(c) + " (" + kChannel[c] + ")");
  return join(s, ", ");
}

}  // namespace

// ---- conventions

nlohmann::json Conventions::to_json_value() const {
  nlohmann::json j;
  j["contract"] = contract.to_json_value();
  j["rotation"] = to_string(rotation);
  j["gripper_range"] = to_string(gripper_range);
  j["action"] = to_string(action);
  return j;
}

Conventions Conventions::from_json_value(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) throw InputError(source, "", "a declared convention must be a JSON object");
  Conventions c;
  const bool bare = j.contains("permutation");
  try {
    c.contract = Contract::from_json_value(bare ? j : j.value("contract", Contract::identity().to_json_value()));
  } catch (const InputError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw InputError(source, "contract", e.what());
  }
  if (bare) return c;
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "contract" && it.key() != "rotation" && it.key() != "gripper_range" && it.key() != "action" && it.key() != "recorded")
      throw InputError(source, it.key(), "unknown key (expected contract, rotation, gripper_range, action, recorded)");
  const auto text = [&](const char* key) -> std::optional<std::string> {
    if (!j.contains(key)) return std::nullopt;
    if (!j[key].is_string()) throw InputError(source, key, "must be a string");
    return j[key].get<std::string>();
  };
  if (auto s = text("rotation")) {
    auto r = parse_rotation_rep(*s);
    if (!r) throw InputError(source, "rotation", "must be axis_angle, euler_xyz or euler_zyx (got " + quote_input(*s) + ")");
    c.rotation = *r;
  }
  if (auto s = text("gripper_range")) {
    auto r = parse_gripper_range(*s);
    if (!r) throw InputError(source, "gripper_range", "must be \"[-1, 1]\" or \"[0, 1]\" (got " + quote_input(*s) + ")");
    c.gripper_range = *r;
  }
  if (auto s = text("action")) {
    auto r = parse_action_kind(*s);
    if (!r) throw InputError(source, "action", "must be command, next_state or current_state (got " + quote_input(*s) + ")");
    c.action = *r;
  }
  return c;
}

// ---- the log

std::size_t ActionLog::transitions() const {
  std::size_t n = 0;
  for (const auto& e : episodes) n += std::min(e.actions.size(), e.poses.empty() ? 0 : e.poses.size() - 1);
  return n;
}

ActionLog ActionLog::head(std::size_t max_transitions) const {
  ActionLog out = *this;
  out.episodes.clear();
  std::size_t left = max_transitions;
  for (const auto& e : episodes) {
    if (left == 0) break;
    const std::size_t n = std::min(e.actions.size(), e.poses.empty() ? 0 : e.poses.size() - 1);
    if (n <= left) {
      out.episodes.push_back(e);
      left -= n;
    } else {
      LogEpisode cut;
      cut.actions.assign(e.actions.begin(), e.actions.begin() + static_cast<std::ptrdiff_t>(left));
      cut.poses.assign(e.poses.begin(), e.poses.begin() + static_cast<std::ptrdiff_t>(left + 1));
      out.episodes.push_back(std::move(cut));
      left = 0;
    }
  }
  return out;
}

void validate_log(const ActionLog& log) {
  for (std::size_t e = 0; e < log.episodes.size(); ++e) {
    const auto& ep = log.episodes[e];
    const auto where = [&](std::size_t t, const char* field) {
      return "episode " + std::to_string(e) + " step " + std::to_string(t) + ": " + field;
    };
    if (ep.poses.size() != ep.actions.size() && ep.poses.size() != ep.actions.size() + 1)
      throw InputError(log.source, "episode " + std::to_string(e),
                       std::to_string(ep.actions.size()) + " actions but " + std::to_string(ep.poses.size()) +
                           " poses (need as many, or one more)");
    for (std::size_t t = 0; t < ep.actions.size(); ++t)
      if (!ep.actions[t].allFinite()) throw InputError(log.source, where(t, "action"), "not a finite number");
    for (std::size_t t = 0; t < ep.poses.size(); ++t) {
      const auto& p = ep.poses[t];
      if (!p.position.allFinite()) throw InputError(log.source, where(t, "tcp position"), "not a finite number");
      if (!p.quaternion.allFinite()) throw InputError(log.source, where(t, "tcp quaternion"), "not a finite number");
      if (!(p.quaternion.norm() > 1e-9)) throw InputError(log.source, where(t, "tcp quaternion"), "zero quaternion");
      if (p.fingers && !p.fingers->allFinite()) throw InputError(log.source, where(t, "fingers"), "not a finite number");
    }
  }
  if (log.transitions() == 0)
    throw InputError(log.source, "", "no transition (an episode needs two poses and an action between them)");
}

std::string validate(const AuditOptions& o) {
  if (!(o.confidence_floor > 0.0 && o.confidence_floor <= 1.0))
    return "audit options: confidence_floor must be in (0, 1] (got " + fmt("%g", o.confidence_floor) + ")";
  if (!(o.misspec_ratio > 0.0) || !std::isfinite(o.misspec_ratio))
    return "audit options: misspec_ratio must be finite and > 0 (got " + fmt("%g", o.misspec_ratio) + ")";
  if (!(o.min_excitation >= 0.0) || !std::isfinite(o.min_excitation))
    return "audit options: min_excitation must be finite and >= 0 (got " + fmt("%g", o.min_excitation) + ")";
  if (!(o.gain_tolerance >= 1.0) || !std::isfinite(o.gain_tolerance))
    return "audit options: gain_tolerance must be finite and >= 1 (got " + fmt("%g", o.gain_tolerance) + ")";
  if (!(o.min_rotation_spread >= 0.0) || !std::isfinite(o.min_rotation_spread))
    return "audit options: min_rotation_spread must be finite and >= 0";
  if (o.model) {
    try {
      o.model->validate();
    } catch (const std::invalid_argument& e) {
      return std::string("audit options: model: ") + e.what();
    }
  }
  return {};
}

int AuditResult::exit_code() const {
  switch (status) {
    case Status::kPass: return 0;
    case Status::kMismatch: return 1;
    default: return 3;
  }
}

const AuditField* AuditResult::field(std::string_view name) const {
  for (const auto& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

// ---- identification

namespace {

constexpr int kModes = adapt::GrammarBelief::kModes;
constexpr int kSK = adapt::GrammarBelief::kSigns * adapt::GrammarBelief::kScales;
constexpr int kFrames = 2;
constexpr int kPerms = 720;

using Cells = std::vector<double>;  // [f][m][i][j][sk]
inline std::size_t cidx(int f, int m, int i, int j, int sk) {
  return static_cast<std::size_t>(((((f * kModes + m) * kPoseDim + i) * kPoseDim + j) * kSK) + sk);
}

struct Step {
  Action raw;
  Pose6 response;                      // measured, physical units
  Pose6 cumulative;                    // Σ of the episode's responses through this step
  Mat3 R;                              // TCP orientation before the step
  Vec3 pos, next_pos;
  std::optional<double> finger_next;   // mean finger position after the step
  bool first{false};                   // first step of an episode
  int unit{0};                         // the jackknife's unit: the episode, or a quarter of a log of < 4 episodes
};

// No single episode decides a field: the units left out one at a time are the episodes, or in a log of
// fewer than four episodes, each episode cut into equal contiguous parts (four parts or more in all).
constexpr std::size_t kMinUnits = 4;

std::vector<std::vector<Step>> transitions_of(const ActionLog& log) {
  std::vector<std::vector<Step>> out;
  for (const auto& ep : log.episodes) {
    std::vector<Step> steps;
    const std::size_t n = std::min(ep.actions.size(), ep.poses.empty() ? 0 : ep.poses.size() - 1);
    for (std::size_t t = 0; t < n; ++t) {
      const TcpPose& a = ep.poses[t];
      const TcpPose& b = ep.poses[t + 1];
      Step s;
      s.raw = ep.actions[t];
      const Eigen::Vector4d qa = a.quaternion / a.quaternion.norm();
      const Eigen::Vector4d qb = b.quaternion / b.quaternion.norm();
      s.response.head<3>() = b.position - a.position;
      const Eigen::Vector4d qa_conj(qa[0], -qa[1], -qa[2], -qa[3]);
      s.response.tail<3>() = adapt::quat_to_rotvec(adapt::quat_multiply(qb, qa_conj));
      s.R = Eigen::Quaterniond(qa[0], qa[1], qa[2], qa[3]).toRotationMatrix();
      s.pos = a.position;
      s.next_pos = b.position;
      if (b.fingers) s.finger_next = 0.5 * ((*b.fingers)[0] + (*b.fingers)[1]);
      s.first = t == 0;
      s.cumulative = (steps.empty() ? Pose6::Zero() : steps.back().cumulative) + s.response;
      steps.push_back(s);
    }
    if (!steps.empty()) out.push_back(std::move(steps));
  }
  const std::size_t parts = out.size() >= kMinUnits ? 1 : (kMinUnits + out.size() - 1) / std::max<std::size_t>(out.size(), 1);
  int unit = 0;
  for (auto& ep : out) {
    for (std::size_t t = 0; t < ep.size(); ++t) ep[t].unit = unit + static_cast<int>(t * parts / ep.size());
    unit += static_cast<int>(std::min(parts, ep.size()));
  }
  return out;
}

int units_of(const std::vector<std::vector<Step>>& eps) { return eps.empty() ? 0 : eps.back().back().unit + 1; }

// the drive of (target, lag) on raw channel j at step t of an episode (zeros before its start)
double drive(const std::vector<Step>& ep, std::size_t t, Target target, int lag, int j) {
  const auto at = [&](std::size_t d) { return t >= d ? ep[t - d].raw[j] : 0.0; };
  const double x = at(static_cast<std::size_t>(lag));
  return target == Target::kDelta ? x : x - at(static_cast<std::size_t>(lag) + 1);
}

// The response of step t in the coordinates a hypothesis (frame f, target, lag) decodes in, each
// channel divided by `alpha` first. Base frame (f = 0): as measured. Tool frame (f = 1), exactly as
// the controller decodes: the command that moved the robot at step t was decoded `lag` steps earlier,
// under that step's rotation R_{t−L}, so a delta is R_{t−L}ᵀ·response_t; an absolute target is the
// difference of two targets decoded under two rotations, and since the tracked target starts at zero
// with the episode, the cumulative response s_t is the target: R_{t−L}ᵀ·s_t − R_{t−L−1}ᵀ·s_{t−1}.
// (Reading both under the current rotation, as a first version did, is wrong by the turn between
// the two steps times the whole target: at a 1.2 rad excursion it named a tool-frame absolute log
// base frame with flipped signs.) Before the episode's start the rotation is the first step's.
Pose6 working(const std::vector<Step>& ep, std::size_t t, const std::array<double, kPoseDim>& alpha, int f, Target target, int lag) {
  const auto scaled = [&](const Pose6& v) {
    Pose6 y;
    for (int c = 0; c < kPoseDim; ++c) y[c] = v[c] / alpha[static_cast<std::size_t>(c)];
    return y;
  };
  const auto into = [&](std::size_t back, const Pose6& v) {  // v in the tool frame of step t − back
    const Mat3& Rt = ep[t >= back ? t - back : 0].R;
    Pose6 y;
    y.head<3>() = Rt.transpose() * Vec3(v.head<3>());
    y.tail<3>() = Rt.transpose() * Vec3(v.tail<3>());
    return y;
  };
  const auto L = static_cast<std::size_t>(lag);
  if (f == 0) return scaled(ep[t].response);
  if (target == Target::kDelta) return into(L, scaled(ep[t].response));
  const Pose6 now = into(L, scaled(ep[t].cumulative));
  return t == 0 ? now : Pose6(now - into(L + 1, scaled(ep[t - 1].cumulative)));
}

std::array<double, kPoseDim> isotropic(const std::array<double, kPoseDim>& s) {
  std::array<double, kPoseDim> o{};
  for (int g = 0; g < 2; ++g) {
    double m = 0;
    for (int c = 3 * g; c < 3 * g + 3; ++c) m += s[static_cast<std::size_t>(c)] * s[static_cast<std::size_t>(c)];
    for (int c = 3 * g; c < 3 * g + 3; ++c) o[static_cast<std::size_t>(c)] = std::sqrt(m / 3.0);
  }
  return o;
}

// the grammar belief's per-cell evidence, summed over episodes, for both frames; `per_unit` (if
// given) receives each jackknife unit's share (the cells are sums over steps)
Cells evidence(const std::vector<std::vector<Step>>& eps, const std::array<double, kPoseDim>& alpha,
               const std::array<double, kPoseDim>& sigma, std::vector<Cells>* per_unit = nullptr) {
  Cells E(static_cast<std::size_t>(kFrames * kModes * kPoseDim * kPoseDim * kSK), 0.0);
  if (per_unit) per_unit->assign(static_cast<std::size_t>(units_of(eps)), Cells(E.size(), 0.0));
  adapt::ResponseModel unit{{1, 1, 1, 1, 1, 1}, sigma};
  const auto add = [&](Cells& out, int f, const adapt::GrammarBelief& b, double sign) {
    for (int m = 0; m < kModes; ++m)
      for (int i = 0; i < kPoseDim; ++i)
        for (int j = 0; j < kPoseDim; ++j)
          for (int sk = 0; sk < kSK; ++sk) out[cidx(f, m, i, j, sk)] += sign * b.evidence(m, i, j, sk / 7, sk % 7);
  };
  for (int f = 0; f < kFrames; ++f)
    for (const auto& ep : eps) {
      adapt::GrammarBelief b(unit);
      std::array<Pose6, kModes> y;
      for (std::size_t t = 0; t < ep.size(); ++t) {
        if (per_unit && (t == 0 || ep[t].unit != ep[t - 1].unit)) add((*per_unit)[static_cast<std::size_t>(ep[t].unit)], f, b, -1.0);
        if (f == 0) {
          b.update(ep[t].raw, working(ep, t, alpha, 0, Target::kDelta, 0));
        } else {
          for (int m = 0; m < kModes; ++m) {
            const auto& mode = adapt::GrammarBelief::modes()[static_cast<std::size_t>(m)];
            y[static_cast<std::size_t>(m)] = working(ep, t, alpha, 1, mode.target, mode.lag);
          }
          b.update_per_mode(ep[t].raw, y);
        }
        if (per_unit && (t + 1 == ep.size() || ep[t + 1].unit != ep[t].unit)) add((*per_unit)[static_cast<std::size_t>(ep[t].unit)], f, b, 1.0);
      }
      add(E, f, b, 1.0);
    }
  return E;
}

double logsumexp(const double* v, int n) {
  double m = -std::numeric_limits<double>::infinity();
  for (int k = 0; k < n; ++k) m = std::max(m, v[k]);
  double s = 0;
  for (int k = 0; k < n; ++k) s += std::exp(v[k] - m);
  return m + std::log(s);
}

const std::vector<std::array<int, kPoseDim>>& permutations() {
  static const std::vector<std::array<int, kPoseDim>> all = [] {
    std::vector<std::array<int, kPoseDim>> v;
    std::array<int, kPoseDim> p{0, 1, 2, 3, 4, 5};
    do v.push_back(p);
    while (std::next_permutation(p.begin(), p.end()));
    return v;
  }();
  return all;
}

struct Posterior {
  int frame{0}, mode{0};
  std::array<int, kPoseDim> perm{};
  std::array<int, kPoseDim> sk{};           // MAP (sign, scale) index per output channel
  double p_map_h{0};                         // posterior of the MAP (frame, mode, perm)
  double p_contract{0};                      // ... times the MAP cells' (sign, scale)
  std::array<double, kFrames> p_frame{};
  std::array<double, kModes> p_mode{};
  std::array<double, kPoseDim> p_perm{};     // P(π_i = π*_i)
  std::array<double, kPoseDim> p_sign{};
  std::array<double, kPoseDim> p_scale{};
  double p_perm_all{0};                      // P(π = π*)
};

Posterior posterior(const Cells& E) {
  Posterior P;
  // L = log Σ_sk exp E per cell
  std::vector<double> L(static_cast<std::size_t>(kFrames * kModes * kPoseDim * kPoseDim));
  const auto lidx = [](int f, int m, int i, int j) { return static_cast<std::size_t>(((f * kModes + m) * kPoseDim + i) * kPoseDim + j); };
  for (int f = 0; f < kFrames; ++f)
    for (int m = 0; m < kModes; ++m)
      for (int i = 0; i < kPoseDim; ++i)
        for (int j = 0; j < kPoseDim; ++j) L[lidx(f, m, i, j)] = logsumexp(&E[cidx(f, m, i, j, 0)], kSK);
  const auto& perms = permutations();
  std::vector<double> lw(static_cast<std::size_t>(kFrames * kModes * kPerms));
  double best = -std::numeric_limits<double>::infinity();
  std::size_t arg = 0;
  for (int f = 0; f < kFrames; ++f)
    for (int m = 0; m < kModes; ++m)
      for (int p = 0; p < kPerms; ++p) {
        double s = 0;
        for (int i = 0; i < kPoseDim; ++i) s += L[lidx(f, m, i, perms[static_cast<std::size_t>(p)][static_cast<std::size_t>(i)])];
        const std::size_t k = static_cast<std::size_t>((f * kModes + m) * kPerms + p);
        lw[k] = s;
        if (s > best) {  // first maximum: base before tool, lower modes first, identity first
          best = s;
          arg = k;
        }
      }
  double z = 0;
  for (double v : lw) z += std::exp(v - best);
  P.frame = static_cast<int>(arg / (kModes * kPerms));
  P.mode = static_cast<int>((arg / kPerms) % kModes);
  P.perm = perms[arg % kPerms];
  // A[f][m][i][j] = P(f, m, π_i = j)
  std::vector<double> A(L.size(), 0.0);
  for (int f = 0; f < kFrames; ++f)
    for (int m = 0; m < kModes; ++m)
      for (int p = 0; p < kPerms; ++p) {
        const std::size_t k = static_cast<std::size_t>((f * kModes + m) * kPerms + p);
        const double w = std::exp(lw[k] - best) / z;
        P.p_frame[static_cast<std::size_t>(f)] += w;
        P.p_mode[static_cast<std::size_t>(m)] += w;
        const auto& pr = perms[static_cast<std::size_t>(p)];
        if (pr == P.perm) P.p_perm_all += w;
        for (int i = 0; i < kPoseDim; ++i) A[lidx(f, m, i, pr[static_cast<std::size_t>(i)])] += w;
      }
  P.p_map_h = 1.0 / z;
  double cells = 1.0;
  for (int i = 0; i < kPoseDim; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    const int j = P.perm[ii];
    const double* c = &E[cidx(P.frame, P.mode, i, j, 0)];
    int a = 0;
    for (int sk = 1; sk < kSK; ++sk)
      if (c[sk] > c[a]) a = sk;
    P.sk[ii] = a;
    cells *= std::exp(c[a] - L[lidx(P.frame, P.mode, i, j)]);
    double pp = 0, ps = 0, pk = 0;
    for (int f = 0; f < kFrames; ++f)
      for (int m = 0; m < kModes; ++m)
        for (int jj = 0; jj < kPoseDim; ++jj) {
          const double w = A[lidx(f, m, i, jj)];
          if (w < 1e-300) continue;
          if (jj == j) pp += w;
          const double* cc = &E[cidx(f, m, i, jj, 0)];
          const double l = L[lidx(f, m, i, jj)];
          double qs = 0, qk = 0;
          for (int sk = 0; sk < kSK; ++sk) {
            const double q = std::exp(cc[sk] - l);
            if (sk / 7 == a / 7) qs += q;
            if (sk % 7 == a % 7) qk += q;
          }
          ps += w * qs;
          pk += w * qk;
        }
    P.p_perm[ii] = pp;
    P.p_sign[ii] = ps;
    P.p_scale[ii] = pk;
  }
  P.p_contract = P.p_map_h * cells;
  return P;
}

Contract contract_of(const Posterior& P, bool gripper_inverted) {
  ContractFields f;
  const auto& mode = adapt::GrammarBelief::modes()[static_cast<std::size_t>(P.mode)];
  for (int i = 0; i < kPoseDim; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    f.permutation[ii] = P.perm[ii];
    f.sign[ii] = P.sk[ii] / 7 == 0 ? -1 : 1;
    f.scale[ii] = grammar::kScaleGrid[static_cast<std::size_t>(P.sk[ii] % 7)];
  }
  f.target = to_string(mode.target);
  f.frame = P.frame == 0 ? "base" : "tool";
  f.lag = mode.lag;
  f.gripper_inverted = gripper_inverted;
  return Contract::make(f);
}

// per-channel residuals of a contract's replay in the working coordinates
struct Residuals {
  std::array<double, kPoseDim> rms{};
  std::array<double, kPoseDim> rho{};
};

Residuals residuals(const std::vector<std::vector<Step>>& eps, const std::array<double, kPoseDim>& alpha, const Contract& c) {
  Residuals r;
  std::array<double, kPoseDim> ss{}, cross{};
  std::size_t n = 0;
  for (const auto& ep : eps) {
    Pose6 prev = Pose6::Zero();
    for (std::size_t t = 0; t < ep.size(); ++t) {
      const Pose6 y = working(ep, t, alpha, c.frame() == Frame::kTool ? 1 : 0, c.target(), c.lag());
      for (int i = 0; i < kPoseDim; ++i) {
        const auto ii = static_cast<std::size_t>(i);
        const double pred = c.sign()[ii] * c.scale()[ii] * drive(ep, t, c.target(), c.lag(), c.permutation()[ii]);
        const double e = y[i] - pred;
        ss[ii] += e * e;
        if (t > 0) cross[ii] += e * prev[i];
        prev[i] = e;
      }
      ++n;
    }
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(kPoseDim); ++i) {
    r.rms[i] = std::sqrt(ss[i] / static_cast<double>(std::max<std::size_t>(n, 1)));
    r.rho[i] = ss[i] > 0 ? cross[i] / ss[i] : 0.0;
  }
  return r;
}

// ---- the extension's conventions

Mat3 rotation_of(RotationRep rep, const Vec3& v) {
  using Eigen::AngleAxisd;
  switch (rep) {
    case RotationRep::kEulerXyz:
      return (AngleAxisd(v[0], Vec3::UnitX()) * AngleAxisd(v[1], Vec3::UnitY()) * AngleAxisd(v[2], Vec3::UnitZ())).toRotationMatrix();
    case RotationRep::kEulerZyx:
      return (AngleAxisd(v[2], Vec3::UnitZ()) * AngleAxisd(v[1], Vec3::UnitY()) * AngleAxisd(v[0], Vec3::UnitX())).toRotationMatrix();
    default: {
      const double a = v.norm();
      return a > 0 ? AngleAxisd(a, v / a).toRotationMatrix() : Mat3::Identity();
    }
  }
}

Vec3 rotvec_of(const Mat3& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

struct Probability {
  int value{0};
  double confidence{0};
  bool decidable{false};
};

// the rotation representation: Gaussian likelihood of the rotation channels under each representation
// of the MAP's decoded rotation increment (realised angle α·canonical)
std::array<double, 3> rotation_rep_posterior(const std::vector<std::vector<Step>>& eps, const std::array<double, kPoseDim>& alpha,
                                             const std::array<double, kPoseDim>& sigma, const Contract& c, double* separation,
                                             std::array<std::array<double, 3>, 3>* sq_residual) {
  std::array<double, 3> ll{};
  std::array<double, 3> sep{};  // Σ squared standardized distance between the predictions of each pair
  for (const auto& ep : eps)
    for (std::size_t t = 0; t < ep.size(); ++t) {
      Vec3 v;
      for (int i = 3; i < 6; ++i) {
        const auto ii = static_cast<std::size_t>(i);
        v[i - 3] = alpha[ii] * c.sign()[ii] * c.scale()[ii] * drive(ep, t, c.target(), c.lag(), c.permutation()[ii]);
      }
      const std::array<double, kPoseDim> unit{1, 1, 1, 1, 1, 1};
      const Vec3 y = working(ep, t, unit, c.frame() == Frame::kTool ? 1 : 0, c.target(), c.lag()).tail<3>();
      std::array<Vec3, 3> pred;
      for (int r = 0; r < 3; ++r) {
        pred[static_cast<std::size_t>(r)] = rotvec_of(rotation_of(static_cast<RotationRep>(r), v));
        for (int i = 0; i < 3; ++i) {
          const auto ii = static_cast<std::size_t>(i + 3);
          const double e = (y[i] - pred[static_cast<std::size_t>(r)][i]) / (sigma[ii] * std::abs(alpha[ii]));
          ll[static_cast<std::size_t>(r)] -= 0.5 * e * e;
          (*sq_residual)[static_cast<std::size_t>(r)][static_cast<std::size_t>(i)] += (y[i] - pred[static_cast<std::size_t>(r)][i]) * (y[i] - pred[static_cast<std::size_t>(r)][i]);
        }
      }
      for (int a = 0; a < 3; ++a)
        for (int i = 0; i < 3; ++i) {
          const auto ii = static_cast<std::size_t>(i + 3);
          const double d = (pred[static_cast<std::size_t>(a)][i] - pred[static_cast<std::size_t>((a + 1) % 3)][i]) / (sigma[ii] * std::abs(alpha[ii]));
          sep[static_cast<std::size_t>(a)] += d * d;
        }
    }
  *separation = std::min({sep[0], sep[1], sep[2]});
  const double m = std::max({ll[0], ll[1], ll[2]});
  std::array<double, 3> p{};
  double z = 0;
  for (int r = 0; r < 3; ++r) z += (p[static_cast<std::size_t>(r)] = std::exp(ll[static_cast<std::size_t>(r)] - m));
  for (auto& x : p) x /= z;
  return p;
}

double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

}  // namespace

AuditResult audit(const ActionLog& log, const AuditOptions& o) {
  if (const std::string err = validate(o); !err.empty()) throw std::invalid_argument(err);
  validate_log(log);
  const auto eps = transitions_of(log);
  AuditResult R;
  R.source = log.source;
  R.declared = o.declared;
  R.episodes = eps.size();
  R.transitions = log.transitions();
  const double floor = o.confidence_floor;

  // excitation per raw channel
  {
    std::array<double, kPoseDim> ss{};
    for (const auto& ep : eps)
      for (const auto& s : ep)
        for (int j = 0; j < kPoseDim; ++j) ss[static_cast<std::size_t>(j)] += s.raw[j] * s.raw[j];
    for (int j = 0; j < kPoseDim; ++j)
      R.excitation[static_cast<std::size_t>(j)] = std::sqrt(ss[static_cast<std::size_t>(j)] / static_cast<double>(R.transitions));
  }

  // 1. what the action is: a command, or a logged pose
  ActionKind kind = ActionKind::kCommand;
  double kind_conf = 1.0;
  bool kind_decidable = true;
  {
    double m = 0, rn = 0, rc = 0;
    for (const auto& ep : eps)
      for (const auto& s : ep) {
        m += (s.next_pos - s.pos).squaredNorm();
        rn += (s.raw.head<3>() - s.next_pos).squaredNorm();
        rc += (s.raw.head<3>() - s.pos).squaredNorm();
      }
    m = std::sqrt(m / static_cast<double>(R.transitions));
    rn = std::sqrt(rn / static_cast<double>(R.transitions));
    rc = std::sqrt(rc / static_cast<double>(R.transitions));
    if (m <= 1e-12) {
      kind_decidable = false;
      kind_conf = 0.0;
    } else if (rn < 0.25 * m && rn < 0.5 * rc) {
      kind = ActionKind::kNextState;
    } else if (rc < 0.25 * m && rc < 0.5 * rn) {
      kind = ActionKind::kCurrentState;
    }
  }
  const bool commands = kind == ActionKind::kCommand && kind_decidable;

  // 2. the response model: calibrated, or fitted from the log (best single drive per output channel)
  std::array<double, kPoseDim> alpha{}, sigma{};
  if (o.model) {
    alpha = o.model->alpha;
    sigma = o.model->sigma;
  } else {
    R.model_fitted = true;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      double best_explained = -1, best_b = 0, best_res = 0;
      for (int m = 0; m < kModes; ++m) {
        const auto& mode = adapt::GrammarBelief::modes()[static_cast<std::size_t>(m)];
        for (int j = 0; j < kPoseDim; ++j) {
          double sxy = 0, sxx = 0, syy = 0;
          for (const auto& ep : eps)
            for (std::size_t t = 0; t < ep.size(); ++t) {
              const double x = drive(ep, t, mode.target, mode.lag, j), y = ep[t].response[i];
              sxy += x * y;
              sxx += x * x;
              syy += y * y;
            }
          if (sxx <= 0) continue;
          const double explained = sxy * sxy / sxx;
          if (explained > best_explained) {
            best_explained = explained;
            best_b = sxy / sxx;
            best_res = std::max(syy - explained, 0.0);
          }
        }
      }
      alpha[ii] = std::abs(best_b);
      sigma[ii] = std::sqrt(best_res / static_cast<double>(R.transitions));
    }
    // an unexcited channel keeps its group's typical gain, so its evidence is weak rather than undefined
    for (int g = 0; g < 2; ++g) {
      double amax = 0, smax = 0;
      for (int c = 3 * g; c < 3 * g + 3; ++c) {
        amax = std::max(amax, alpha[static_cast<std::size_t>(c)]);
        smax = std::max(smax, sigma[static_cast<std::size_t>(c)]);
      }
      if (amax <= 0) amax = 1.0;
      for (int c = 3 * g; c < 3 * g + 3; ++c) {
        auto& a = alpha[static_cast<std::size_t>(c)];
        auto& s = sigma[static_cast<std::size_t>(c)];
        if (a < 1e-3 * amax) a = amax;
        s = std::max(s, 1e-6 * amax);
        if (smax > 0) s = std::max(s, 1e-3 * smax);
      }
    }
  }
  R.alpha = alpha;
  std::array<double, kPoseDim> sigma_n{};  // calibrated noise in working (normalised) units
  for (int c = 0; c < kPoseDim; ++c)
    sigma_n[static_cast<std::size_t>(c)] = sigma[static_cast<std::size_t>(c)] / std::abs(alpha[static_cast<std::size_t>(c)]);

  // 3. the grammar: two passes, the second with the residual noise scale (inflated for the residuals'
  // serial correlation), so a log the model describes loosely is not over-trusted
  Posterior P;
  Contract map;
  std::array<double, kPoseDim> sigma_used = isotropic(sigma_n);
  std::array<double, kPoseDim> fit_terms{};  // per channel: mean squared residual / calibrated variance
  struct {
    std::array<bool, kPoseDim> perm{}, sign{};
    bool frame{false}, target{false}, lag{false};
  } fragile;  // fields whose MAP changes when one episode is left out
  if (commands) {
    P = posterior(evidence(eps, alpha, sigma_used));
    map = contract_of(P, false);
    const Residuals res = residuals(eps, alpha, map);
    double ratio = 0;
    std::array<double, kPoseDim> inflated{};
    for (int c = 0; c < kPoseDim; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      fit_terms[cc] = (res.rms[cc] / sigma_n[cc]) * (res.rms[cc] / sigma_n[cc]);
      ratio += fit_terms[cc] / kPoseDim;
      const double rho = std::clamp(res.rho[cc], 0.0, 0.95);
      inflated[cc] = std::max(sigma_n[cc], res.rms[cc]) * std::sqrt((1 + rho) / (1 - rho));
    }
    R.fit_ratio = ratio;
    const auto iso = isotropic(inflated);
    R.noise_inflation = std::max(iso[0] / sigma_used[0], iso[3] / sigma_used[3]);
    sigma_used = iso;
    std::vector<Cells> shares;
    Cells E = evidence(eps, alpha, sigma_used, &shares);
    P = posterior(E);
    // No single episode decides a field: in a closed loop one episode's contact or oscillation can
    // outweigh the rest of a short log (on the simulator a lagged contract's rx sign came out backwards
    // at 200 transitions, carried by one of four episodes). Each field's MAP is recomputed with each
    // unit (episode, or quarter of a log of fewer than four) left out; a field that changes is not resolved.
    if (shares.size() >= 2)
      for (std::size_t u = 0; u < shares.size(); ++u) {
        for (std::size_t k = 0; k < E.size(); ++k) E[k] -= shares[u][k];
        const Posterior Q = posterior(E);
        for (std::size_t k = 0; k < E.size(); ++k) E[k] += shares[u][k];
        const auto& qm = adapt::GrammarBelief::modes()[static_cast<std::size_t>(Q.mode)];
        const auto& pm = adapt::GrammarBelief::modes()[static_cast<std::size_t>(P.mode)];
        for (std::size_t i = 0; i < static_cast<std::size_t>(kPoseDim); ++i) {
          if (Q.perm[i] != P.perm[i]) fragile.perm[i] = true;
          if (Q.perm[i] != P.perm[i] || Q.frame != P.frame || Q.sk[i] / 7 != P.sk[i] / 7) fragile.sign[i] = true;
        }
        fragile.frame = fragile.frame || Q.frame != P.frame;
        fragile.target = fragile.target || qm.target != pm.target;
        fragile.lag = fragile.lag || qm.lag != pm.lag;
      }
  }

  // a channel whose source is hardly commanded is not resolved, whatever its posterior: in a closed-loop
  // log a policy's small corrections answer disturbances, which biases their apparent response
  if (commands)
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      if (R.excitation[static_cast<std::size_t>(P.perm[ii])] < o.min_excitation) P.p_perm[ii] = P.p_sign[ii] = P.p_scale[ii] = 0.0;
      if (fragile.perm[ii]) P.p_perm[ii] = 0.0;
      if (fragile.perm[ii] || fragile.sign[ii]) P.p_sign[ii] = P.p_scale[ii] = 0.0;
    }

  // 4. the gripper: range from the numbers, polarity from the fingers (lag of the grammar's MAP)
  GripperRange range = o.declared.gripper_range;
  double range_conf = 0;
  std::string range_reason;
  bool inverted = o.declared.contract.gripper_inverted();
  double polarity_conf = 0;
  std::string polarity_reason;
  bool polarity_checked = log.has_gripper;
  const int map_lag = commands ? adapt::GrammarBelief::modes()[static_cast<std::size_t>(P.mode)].lag : 0;
  if (log.has_gripper) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::size_t n_lo = 0, n_hi = 0, n = 0;
    for (const auto& ep : eps)
      for (const auto& s : ep) {
        const double g = s.raw[kGripper];
        lo = std::min(lo, g);
        hi = std::max(hi, g);
        n_lo += g < 0.1;
        n_hi += g > 0.9;
        ++n;
      }
    if (hi - lo < 0.1) {
      range_reason = "the gripper command never changes; a log that opens and closes the gripper would decide";
    } else if (lo < -0.05) {
      range = GripperRange::kSymmetric;
      range_conf = 1.0;
    } else if (hi <= 1.05 && n_lo > 0 && n_hi > 0) {
      range = GripperRange::kUnit;
      range_conf = 1.0;
    } else {
      range_reason = "the gripper commands do not reach both ends of either range";
    }
    // polarity: fingers after the step against the (lagged, centred) gripper command
    double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    std::size_t m = 0;
    const GripperRange r_used = range_conf > 0 ? range : o.declared.gripper_range;
    for (const auto& ep : eps)
      for (std::size_t t = 0; t < ep.size(); ++t) {
        if (!ep[t].finger_next) continue;
        double g = t >= static_cast<std::size_t>(map_lag) ? ep[t - static_cast<std::size_t>(map_lag)].raw[kGripper] : 0.0;
        if (r_used == GripperRange::kUnit && t >= static_cast<std::size_t>(map_lag)) g = 2 * g - 1;
        const double y = *ep[t].finger_next;
        sx += g;
        sy += y;
        sxx += g * g;
        sxy += g * y;
        syy += y * y;
        ++m;
      }
    if (m < 3) {
      polarity_checked = false;
      polarity_reason = "the log has no finger positions: the gripper's polarity shows only in the fingers";
    } else {
      const double mn = static_cast<double>(m);
      const double vx = sxx - sx * sx / mn, cxy = sxy - sx * sy / mn, vy = syy - sy * sy / mn;
      if (vx <= 1e-12 * mn) {
        polarity_reason = "the gripper command never changes; a log that opens and closes the gripper would decide";
      } else {
        const double b = cxy / vx;
        const double res = std::max(vy - b * cxy, 0.0) / std::max(mn - 2, 1.0);
        // serial correlation of finger positions: effective samples = the number of command changes
        std::size_t changes = 1;
        for (const auto& ep : eps)
          for (std::size_t t = 1; t < ep.size(); ++t) changes += std::abs(ep[t].raw[kGripper] - ep[t - 1].raw[kGripper]) > 0.1;
        const double se = std::sqrt(res / vx) * std::sqrt(mn / static_cast<double>(std::min(changes, m)));
        const double z = se > 0 ? b / se : (b > 0 ? 1e9 : -1e9);
        const double p_not = normal_cdf(z);
        inverted = p_not < 0.5;
        polarity_conf = std::max(p_not, 1 - p_not);
        if (polarity_conf < floor)
          polarity_reason = "the fingers follow the gripper command too weakly; more open and close commands would decide";
      }
    }
  } else {
    range_reason = "the log has no gripper channel";
    polarity_reason = "the log has no gripper channel";
  }

  // 5. the identified conventions
  Conventions id = o.declared;
  id.action = kind_decidable ? kind : o.declared.action;
  if (commands) {
    map = contract_of(P, polarity_checked && polarity_conf > 0 ? inverted : o.declared.contract.gripper_inverted());
    id.contract = map;
    R.map_posterior = P.p_contract;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      R.effective_gain[ii] = alpha[ii] * map.sign()[ii] * map.scale()[ii];
    }
  } else {
    auto f = o.declared.contract.fields();
    f.gripper_inverted = polarity_checked && polarity_conf > 0 ? inverted : o.declared.contract.gripper_inverted();
    id.contract = Contract::make(f);
  }
  id.gripper_range = range_conf > 0 ? range : o.declared.gripper_range;
  std::array<double, 3> rep_p{1.0 / 3, 1.0 / 3, 1.0 / 3};
  double rep_separation = 0;
  if (commands) {
    std::array<double, kPoseDim> s_phys{};
    for (int c = 0; c < kPoseDim; ++c) s_phys[static_cast<std::size_t>(c)] = sigma_used[static_cast<std::size_t>(c)];
    std::array<std::array<double, 3>, 3> sq{};
    rep_p = rotation_rep_posterior(eps, alpha, s_phys, map, &rep_separation, &sq);
    int best = 0;
    for (int r = 1; r < 3; ++r)
      if (rep_p[static_cast<std::size_t>(r)] > rep_p[static_cast<std::size_t>(best)]) best = r;
    id.rotation = static_cast<RotationRep>(best);
    // the fit of the rotation channels under the identified representation (the grammar's linear
    // replay above has the other representations' second-order terms in its residual)
    double ratio = 0;
    for (int c = 0; c < 3; ++c) ratio += fit_terms[static_cast<std::size_t>(c)];
    for (int c = 0; c < 3; ++c) {
      const auto cc = static_cast<std::size_t>(c + 3);
      const double rms = std::sqrt(sq[static_cast<std::size_t>(best)][static_cast<std::size_t>(c)] / static_cast<double>(R.transitions)) / std::abs(alpha[cc]);
      ratio += std::min(fit_terms[cc], (rms / sigma_n[cc]) * (rms / sigma_n[cc]));
    }
    R.fit_ratio = ratio / kPoseDim;
  }
  R.identified = id;

  // 6. the fields
  const Contract& dc = o.declared.contract;
  const std::string not_commands =
      kind_decidable ? "the logged actions are poses, not commands of the grammar"
                     : "the TCP does not move in the log: nothing responds to the commands";
  const auto per_channel = [&](Field f, const std::array<double, kPoseDim>& conf) {
    AuditField a;
    a.name = to_string(f);
    a.declared = field_value(dc, f);
    if (!commands) {
      a.checked = false;
      a.identified = a.declared;
      a.reason = not_commands;
      return a;
    }
    a.confidence = 1.0;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      a.confidence = std::min(a.confidence, conf[ii]);
      if (conf[ii] < floor) a.unresolved_channels.push_back(i);
    }
    a.resolved = a.unresolved_channels.empty();
    // identified value, "?" on unresolved channels; diff over resolved channels
    std::vector<std::string> parts, diffs;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      const bool ok = conf[ii] >= floor;
      std::string v, dv;
      if (f == Field::kPermutation) {
        v = std::to_string(map.permutation()[ii]);
        dv = std::to_string(dc.permutation()[ii]);
      } else if (f == Field::kSign) {
        v = std::to_string(map.sign()[ii]);
        dv = std::to_string(dc.sign()[ii]);
      } else {
        v = python_float_repr(map.scale()[ii]);
        dv = python_float_repr(dc.scale()[ii]);
      }
      parts.push_back(ok ? v : "?");
      if (ok && v != dv) {
        if (f == Field::kPermutation)
          diffs.push_back("output channel " + std::to_string(i) + " (" + kChannel[i] + ") reads raw channel " + v + ", declared " + dv);
        else if (f == Field::kSign)
          diffs.push_back("channel " + std::to_string(i) + " (" + kChannel[i] + ") sign FLIPPED");
        else
          diffs.push_back("channel " + std::to_string(i) + " (" + kChannel[i] + ") scale " + dv + "->" + v +
                          (R.model_fitted ? " (relative to the fitted gain)" : ""));
      }
    }
    a.identified = "(" + join(parts, ", ") + ")";
    if (a.resolved && f != Field::kScale) {
      a.diff = diff_sentence(dc, map, f);
    } else {
      a.diff = join(diffs, "; ");
    }
    if (f == Field::kScale && a.resolved) a.diff = join(diffs, "; ");
    if (!a.resolved) {
      std::vector<int> raw;
      for (int i : a.unresolved_channels) raw.push_back(map.permutation()[static_cast<std::size_t>(i)]);
      std::string weak;
      for (int j = 0; j < kPoseDim; ++j)
        if (R.excitation[static_cast<std::size_t>(j)] < o.min_excitation) weak += (weak.empty() ? "" : ", ") + std::to_string(j);
      a.reason = "not resolved on output channel(s) " + channel_list(a.unresolved_channels) +
                 (weak.empty() ? "" : "; raw channel(s) " + weak + " hardly move (RMS command < " + fmt("%g", o.min_excitation) + ")") +
                 "; a log that commands every channel, positive and negative, on its own and in reversals, would decide";
      if (f == Field::kSign || f == Field::kPermutation)
        a.reason += "; with the TCP orientation nearly constant, a tool-frame contract equals a base-frame one with other signs and channels, so also rotate the TCP";
      std::vector<int> one;
      for (int i : a.unresolved_channels)
        if (fragile.perm[static_cast<std::size_t>(i)] || (f != Field::kPermutation && fragile.sign[static_cast<std::size_t>(i)])) one.push_back(i);
      if (!one.empty())
        a.reason += "; on channel(s) " + channel_list(one) + " one episode decides (leaving it out changes the answer): more episodes would decide";
    }
    return a;
  };
  R.fields.push_back(per_channel(Field::kPermutation, P.p_perm));
  R.fields.push_back(per_channel(Field::kSign, P.p_sign));
  {
    AuditField s = per_channel(Field::kScale, P.p_scale);
    if (commands && !R.model_fitted) {
      // The calibrated gain describes the calibration's motion (random walks); a log's motion runs at
      // another gain (sustained commands, contacts), so a channel's scale is the set of grid values
      // within the gain tolerance of the log's least-squares gain / calibrated gain (widened by two
      // standard errors). The declaration agrees if its scale is in that band; it differs if the
      // channel's routing is resolved and its declared scale is outside the band.
      const int f = map.frame() == Frame::kTool ? 1 : 0;
      std::vector<std::string> parts, diffs;
      s.unresolved_channels.clear();
      s.confidence = 1.0;
      for (int i = 0; i < kPoseDim; ++i) {
        const auto ii = static_cast<std::size_t>(i);
        double sxy = 0, sxx = 0;
        std::vector<double> uxy(static_cast<std::size_t>(units_of(eps)), 0.0), uxx(uxy.size(), 0.0);
        for (const auto& ep : eps)
          for (std::size_t t = 0; t < ep.size(); ++t) {
            const double d = drive(ep, t, map.target(), map.lag(), map.permutation()[ii]);
            const double xy = working(ep, t, alpha, f, map.target(), map.lag())[i] * d;
            sxy += xy;
            sxx += d * d;
            uxy[static_cast<std::size_t>(ep[t].unit)] += xy;
            uxx[static_cast<std::size_t>(ep[t].unit)] += d * d;
          }
        const double g = sxx > 0 ? std::abs(sxy / sxx) : 0.0;
        // the standard error: the noise model's, or the jackknife's over episodes if larger (a closed
        // loop's episodes run at different gains: contacts, oscillations under a lag)
        double se = sxx > 0 ? sigma_used[ii] / std::sqrt(sxx) : std::numeric_limits<double>::infinity();
        if (uxy.size() >= 2 && sxx > 0) {
          std::vector<double> gu;
          for (std::size_t u = 0; u < uxy.size(); ++u)
            if (sxx - uxx[u] > 0) gu.push_back(std::abs((sxy - uxy[u]) / (sxx - uxx[u])));
          if (gu.size() == uxy.size()) {
            double mean = 0, ss = 0;
            for (double x : gu) mean += x / static_cast<double>(gu.size());
            for (double x : gu) ss += (x - mean) * (x - mean);
            se = std::max(se, std::sqrt(ss * static_cast<double>(gu.size() - 1) / static_cast<double>(gu.size())));
          } else {
            se = std::numeric_limits<double>::infinity();  // one unit carries all of the channel's drive
          }
        }
        const double lo = g / o.gain_tolerance - 2 * se, hi = g * o.gain_tolerance + 2 * se;
        R.scale_band[ii] = {std::max(lo, 0.0), hi};
        std::vector<std::string> in;
        for (double k : grammar::kScaleGrid)
          if (k >= lo && k <= hi) in.push_back(python_float_repr(k));
        const bool routed = P.p_perm[ii] >= floor && P.p_sign[ii] >= floor;
        const bool ok = routed && !in.empty() && in.size() < grammar::kScaleGrid.size();
        if (!ok) {
          s.unresolved_channels.push_back(i);
          s.confidence = 0.0;
        }
        parts.push_back(ok ? join(in, "|") : "?");
        const double dk = dc.scale()[ii];
        if (ok && !(dk >= lo && dk <= hi))
          diffs.push_back("channel " + std::to_string(i) + " (" + kChannel[i] + ") scale " + python_float_repr(dk) + "->" + join(in, " or ") +
                          " (the log's gain is " + fmt("%.2f", g) + "x the calibrated one)");
      }
      s.identified = "(" + join(parts, ", ") + ")";
      s.resolved = s.unresolved_channels.empty();
      s.diff = join(diffs, "; ");
      s.reason.clear();
      if (!s.resolved)
        s.reason = "not resolved on output channel(s) " + channel_list(s.unresolved_channels) +
                   ": their routing is not resolved, or the log's gain fits no grid scale or every one within the gain tolerance x" +
                   fmt("%.2f", o.gain_tolerance) + "; longer motion on those channels would decide";
    }
    if (R.model_fitted && commands) {
      s.checked = false;
      s.reason = "no response calibration: a log cannot separate the contract's scale from the robot's response gain; "
                 "scales are relative to the gain fitted from this log (effective gains per output channel in the report)";
    }
    R.fields.push_back(std::move(s));
  }
  const auto scalar = [&](const std::string& name, const std::string& declared, const std::string& identified, double conf,
                          bool checked, std::string reason, std::string diff) {
    AuditField a;
    a.name = name;
    a.declared = declared;
    a.identified = identified;
    a.confidence = conf;
    a.checked = checked;
    a.resolved = checked && conf >= floor;
    if (a.resolved && declared != identified) a.diff = std::move(diff);
    if (!a.resolved) a.reason = std::move(reason);
    return a;
  };
  const auto& mode = adapt::GrammarBelief::modes()[static_cast<std::size_t>(P.mode)];
  double p_target = 0, p_lag = 0;
  for (int m = 0; m < kModes; ++m) {
    const auto& mm = adapt::GrammarBelief::modes()[static_cast<std::size_t>(m)];
    if (mm.target == mode.target) p_target += P.p_mode[static_cast<std::size_t>(m)];
    if (mm.lag == mode.lag) p_lag += P.p_mode[static_cast<std::size_t>(m)];
  }
  R.fields.push_back(scalar("target", to_string(dc.target()), commands ? to_string(map.target()) : to_string(dc.target()), p_target,
                            commands, commands ? "delta and absolute targets are not told apart; commands that change from step to step (reversals) would decide" : not_commands,
                            "target encoding differs: declared " + std::string(to_string(dc.target())) + ", the log is " + to_string(map.target())));
  // a scalar field that one episode decides is not resolved
  const auto unless_fragile = [&](bool is_fragile) {
    AuditField& a = R.fields.back();
    if (!is_fragile || !a.resolved) return;
    a.resolved = false;
    a.diff.clear();
    a.reason = "one episode decides it (leaving it out changes the answer); more episodes would decide";
  };
  unless_fragile(fragile.target);
  double spread = 0;
  for (const auto& ep : eps)
    for (const auto& s : ep) spread = std::max(spread, Eigen::AngleAxisd(eps.front().front().R.transpose() * s.R).angle());
  R.fields.push_back(scalar("frame", to_string(dc.frame()), commands ? to_string(map.frame()) : to_string(dc.frame()),
                            P.p_frame[static_cast<std::size_t>(P.frame)], commands,
                            commands ? "base and tool frames are not told apart (the TCP orientation varies by " + fmt("%.2f", spread) +
                                           " rad over the log); a log in which the TCP turns by at least " + fmt("%.1f", std::max(o.min_rotation_spread, 0.2)) +
                                           " rad while translating would decide"
                                     : not_commands,
                            "reference frame differs: declared " + std::string(to_string(dc.frame())) + ", the log is " + to_string(map.frame())));
  unless_fragile(fragile.frame);
  R.fields.push_back(scalar("lag", std::to_string(dc.lag()), commands ? std::to_string(map.lag()) : std::to_string(dc.lag()), p_lag, commands,
                            commands ? "the actuation lag is not resolved; commands that change abruptly (steps, reversals) would decide" : not_commands,
                            "actuation lag differs: declared " + std::to_string(dc.lag()) + " step(s), the log shows " + std::to_string(map.lag()) + " step(s)"));
  unless_fragile(fragile.lag);
  const auto grip_words = [](bool inv) { return std::string(inv ? "inverted (+1 closes)" : "not inverted (+1 opens)"); };
  R.fields.push_back(scalar("gripper_inverted", grip_words(dc.gripper_inverted()), grip_words(id.contract.gripper_inverted()),
                            polarity_conf, polarity_checked, polarity_reason,
                            "gripper polarity differs: declared " + grip_words(dc.gripper_inverted()) + ", the fingers show " +
                                grip_words(id.contract.gripper_inverted())));
  R.fields.push_back(scalar("gripper_range", to_string(o.declared.gripper_range), to_string(id.gripper_range), range_conf, log.has_gripper,
                            range_reason,
                            "gripper range differs: declared " + std::string(to_string(o.declared.gripper_range)) + ", the logged gripper commands span " +
                                to_string(id.gripper_range)));
  {
    const double conf = rep_p[static_cast<std::size_t>(id.rotation)];
    // the representations differ at second order only (half the cross products of the angles): when even
    // a perfect fit could not reach the floor (expected log-odds below log(floor / (1 - floor))), the
    // log cannot tell them apart, and the field is not checked rather than unresolved
    const double needed = 2.0 * std::log(std::max(floor, 0.5) / std::max(1.0 - floor, 1e-12));
    const bool rep_checkable = commands && rep_separation >= needed;
    R.fields.push_back(scalar("rotation", to_string(o.declared.rotation), rep_checkable ? to_string(id.rotation) : to_string(o.declared.rotation),
                              rep_checkable ? conf : 0.0, rep_checkable,
                              commands ? "the rotation representations differ only at second order (half the cross products of the angles): "
                                         "the log's rotations separate them by " + fmt("%.2g", rep_separation) + " (squared noise units; " +
                                         fmt("%.2g", needed) + " needed); simultaneous rotation commands on two or more axes, well above the noise, would decide"
                                       : not_commands,
                              "rotation representation differs: declared " + describe(o.declared.rotation) + ", the log's rotation deltas are " +
                                  describe(id.rotation)));
  }
  R.fields.push_back(scalar("action", to_string(o.declared.action), to_string(id.action), kind_conf, true,
                            "the TCP does not move in the log, so the actions cannot be compared with the poses",
                            "the logged action differs: declared " + action_words(o.declared.action) + ", the log's action is " + action_words(id.action)));

  // 7. the verdict (the self-test's rules, per field and channel)
  std::vector<std::string> diffs, unresolved;
  for (const auto& f : R.fields) {
    if (!f.checked) continue;
    if (!f.diff.empty()) diffs.push_back(f.diff);
    if (!f.resolved) unresolved.push_back(f.name);
  }
  if (commands && R.fit_ratio > o.misspec_ratio) {
    R.status = Status::kInconclusive;
    R.reason = "response misspecification: the best contract of the grammar fits the log at " + fmt("%.1f", R.fit_ratio) +
               "x the calibrated noise variance (threshold " + fmt("%.1f", o.misspec_ratio) +
               "x): the log's controller or response is outside what the grammar and calibration describe. Abstaining.";
  } else if (!diffs.empty()) {
    R.status = Status::kMismatch;
    R.reason = join(diffs, "; ");
    if (!unresolved.empty()) R.reason += " (note: field(s) [" + join(unresolved, ", ") + "] not resolved and not part of this verdict)";
  } else if (!unresolved.empty()) {
    R.status = Status::kInconclusive;
    R.reason = "the log does not decide field(s) [" + join(unresolved, ", ") + "]. Abstaining rather than guessing.";
  } else {
    R.status = Status::kPass;
    R.reason = "every checked field resolved and agrees with the declaration";
  }
  return R;
}

// ---- reports

nlohmann::json to_json_value(const AuditResult& r) {
  nlohmann::json j;
  j["status"] = to_string(r.status);
  j["exit_code"] = r.exit_code();
  j["reason"] = r.reason;
  j["source"] = r.source;
  j["declared"] = r.declared.to_json_value();
  j["identified"] = r.identified.to_json_value();
  j["identified_contract_sha256"] = r.identified.contract.sha256();
  j["map_posterior"] = r.map_posterior;
  j["fit_ratio"] = r.fit_ratio;
  j["noise_inflation"] = r.noise_inflation;
  j["model_fitted"] = r.model_fitted;
  j["alpha"] = r.alpha;
  j["effective_gain"] = r.effective_gain;
  j["scale_band"] = r.scale_band;
  j["excitation"] = r.excitation;
  j["episodes"] = r.episodes;
  j["transitions"] = r.transitions;
  nlohmann::json fields = nlohmann::json::object();
  for (const auto& f : r.fields) {
    nlohmann::json x;
    x["declared"] = f.declared;
    x["identified"] = f.identified;
    x["confidence"] = f.confidence;
    x["checked"] = f.checked;
    x["resolved"] = f.resolved;
    x["unresolved_channels"] = f.unresolved_channels;
    x["diff"] = f.diff;
    x["reason"] = f.reason;
    fields[f.name] = x;
  }
  j["fields"] = fields;
  return j;
}

std::string to_json(const AuditResult& r) { return to_json_value(r).dump(2) + "\n"; }

std::string to_text(const AuditResult& r) {
  std::ostringstream s;
  s << "ActionShift log audit: " << r.source << "\n";
  s << "  " << r.episodes << " episode(s), " << r.transitions << " transitions; response model "
    << (r.model_fitted ? "fitted from the log (scale reported relative to it)" : "calibrated") << "\n\n";
  s << "VERDICT: " << to_string(r.status) << " (exit " << r.exit_code() << ")\n  " << r.reason << "\n\n";
  s << "field              declared                        identified                      confidence\n";
  for (const auto& f : r.fields) {
    char line[512];
    std::snprintf(line, sizeof line, "%-18s %-31s %-31s %s\n", f.name.c_str(), f.declared.c_str(), f.identified.c_str(),
                  f.checked ? fmt("%.4f", f.confidence).c_str() : "not checked");
    s << line;
  }
  bool any = false;
  for (const auto& f : r.fields)
    if (!f.reason.empty()) {
      if (!any) s << "\nNot decided by this log:\n";
      any = true;
      s << "  " << f.name << ": " << f.reason << "\n";
    }
  s << "\nIdentified contract (MAP over the grammar, posterior " << fmt("%.4g", r.map_posterior) << "): " << r.identified.contract.to_json() << "\n";
  s << "Effective gain per output channel (response per unit command):";
  for (double g : r.effective_gain) s << " " << fmt("%.4g", g);
  s << "\nFit: " << fmt("%.2f", r.fit_ratio) << "x the " << (r.model_fitted ? "fitted" : "calibrated")
    << " noise variance; posterior computed with the noise scale x" << fmt("%.2f", r.noise_inflation) << "\n";
  s << "Command RMS per raw channel:";
  for (double g : r.excitation) s << " " << fmt("%.3f", g);
  s << "\n";
  return s.str();
}

}  // namespace actionshift::selftest
