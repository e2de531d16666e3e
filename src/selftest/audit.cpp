// Audit a log (docs/audit.md): the identification core and its reports.
#include "actionshift/selftest/audit.hpp"

#include "audit_detail.hpp"

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

using detail::fmt;
using detail::kChannel;

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
  if (!(o.min_explained >= 0.0 && o.min_explained < 1.0))
    return "audit options: min_explained must be in [0, 1) (got " + fmt("%g", o.min_explained) + ")";
  if (!(o.min_margin >= 0.0) || !std::isfinite(o.min_margin))
    return "audit options: min_margin must be finite and >= 0 (got " + fmt("%g", o.min_margin) + ")";
  if (!(o.max_coupling > 0.0 && o.max_coupling <= 1.0))
    return "audit options: max_coupling must be in (0, 1] (got " + fmt("%g", o.max_coupling) + ")";
  if (!(o.outlier_z > 0.0))
    return "audit options: outlier_z must be > 0 (got " + fmt("%g", o.outlier_z) + ")";
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

// ---- identification (the evidence model: audit_evidence.cpp)

namespace {

using detail::Step;
using detail::drive;
using detail::working;

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
                                             std::array<std::array<double, 3>, 3>* sq_residual,
                                             std::vector<std::array<double, 3>>* unit_sse) {
  unit_sse->assign(static_cast<std::size_t>(detail::units_of(eps)), std::array<double, 3>{});
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
          (*unit_sse)[static_cast<std::size_t>(ep[t].unit)][static_cast<std::size_t>(r)] += e * e;
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

// the share of the finger positions' variance the gripper command must explain for a polarity to be
// read from them (a design constant, fixed before the second evaluation set was recorded)
constexpr double kMinFingerR2 = 0.5;

}  // namespace

AuditResult audit(const ActionLog& log, const AuditOptions& o) {
  if (const std::string err = validate(o); !err.empty()) throw std::invalid_argument(err);
  validate_log(log);
  const auto eps = detail::transitions_of(log);
  AuditResult R;
  R.source = log.source;
  R.declared = o.declared;
  R.episodes = eps.size();
  R.transitions = log.transitions();
  const double floor = o.confidence_floor;
  R.committed_raw.fill(-1);
  R.committed_sign.fill(0);
  R.scale_committed.fill(false);

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

  // 2. the response model: a calibration's gains, or none (gains then in physical units per command)
  std::array<double, kPoseDim> alpha{1, 1, 1, 1, 1, 1};
  if (o.model) alpha = o.model->alpha;
  R.model_fitted = !o.model;

  // 3. the evidence: which hypotheses the log cannot exclude, and what they agree on
  detail::Evidence ev;
  Contract map = o.declared.contract;
  std::array<double, kPoseDim> sigma_n{};  // noise scale of the best mode's residuals (working units)
  std::array<double, kPoseDim> perm_conf{}, sign_conf{};
  if (commands) {
    detail::EvidenceOptions eo;
    eo.alpha = alpha;
    eo.calibrated = o.model.has_value();
    eo.z = floor >= 1.0 ? 40.0 : detail::normal_quantile(floor);
    eo.min_explained = o.min_explained;
    eo.min_excitation = o.min_excitation;
    eo.gain_tolerance = o.gain_tolerance;
    eo.outlier_z = o.outlier_z;
    eo.min_margin = o.min_margin;
    eo.max_coupling = o.max_coupling;
    ev = detail::identify(eps, R.excitation, eo);
    const detail::Mode& bm = ev.modes[static_cast<std::size_t>(ev.best)];
    ContractFields f;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      f.permutation[ii] = ev.map_perm[ii];
      f.sign[ii] = ev.map_sign[ii];
      // the identified scale is the log's own gain (calibrated), never rounded onto the grid
      f.scale[ii] = o.model ? std::max(std::round(ev.map_gain[ii] * 100.0) / 100.0, 0.01) : 1.0;
      const auto& c = ev.channel[ii];
      // a committed channel's confidence: its t statistic mapped so that the test's threshold is the floor
      const double conf = std::abs(c.t) >= ev.t_critical ? 0.5 * std::erfc(-(std::abs(c.t) * eo.z / ev.t_critical) / std::sqrt(2.0)) : 0.0;
      perm_conf[ii] = c.routed ? std::max(conf, floor) : 0.0;
      sign_conf[ii] = c.sign_committed ? std::max(conf, floor) : 0.0;
      if (c.routed) R.committed_raw[ii] = c.raw;
      if (c.sign_committed) R.committed_sign[ii] = c.sign;
      sigma_n[ii] = std::max(ev.residual_rms[ii], 1e-12);
    }
    f.target = to_string(bm.target);
    f.frame = bm.frame == 0 ? "base" : "tool";
    f.lag = bm.lag;
    f.gripper_inverted = o.declared.contract.gripper_inverted();
    map = Contract::make(f);
    R.outlier_rows = ev.outlier_rows;
    R.evidence_t = ev.null_t;
    R.t_critical = ev.t_critical;
    int plausible = 0;
    for (bool p : ev.plausible) plausible += p ? 1 : 0;
    R.plausible_modes = plausible;
    // misspecification (calibrated model only): the best mode's residual against the calibrated noise
    if (o.model) {
      double ratio = 0;
      for (int c = 0; c < kPoseDim; ++c) {
        const double s = o.model->sigma[static_cast<std::size_t>(c)] / std::abs(alpha[static_cast<std::size_t>(c)]);
        ratio += std::pow(ev.residual_rms[static_cast<std::size_t>(c)] / s, 2) / kPoseDim;
      }
      R.fit_ratio = ratio;
      double infl = 0;
      for (int c = 0; c < kPoseDim; ++c) {
        const double s = o.model->sigma[static_cast<std::size_t>(c)] / std::abs(alpha[static_cast<std::size_t>(c)]);
        infl = std::max(infl, ev.residual_rms[static_cast<std::size_t>(c)] / s);
      }
      R.noise_inflation = std::max(infl, 1.0);
    }
  }

  // 4. the gripper: range from the numbers, polarity from the fingers (the best mode's lag)
  GripperRange range = o.declared.gripper_range;
  double range_conf = 0;
  bool range_checked = log.has_gripper;
  std::string range_reason;
  bool inverted = o.declared.contract.gripper_inverted();
  double polarity_conf = 0;
  std::string polarity_reason;
  bool polarity_checked = log.has_gripper;
  const int map_lag = commands ? map.lag() : 0;
  if (log.has_gripper) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::size_t n_lo = 0, n_hi = 0, n_ends = 0, n_all = 0;
    for (const auto& ep : eps)
      for (const auto& s : ep) {
        const double g = s.raw[kGripper];
        lo = std::min(lo, g);
        hi = std::max(hi, g);
        n_lo += g < 0.1;
        n_hi += g > 0.9;
        n_ends += std::abs(g) < 0.05 || std::abs(g - 1.0) < 0.05;
        ++n_all;
      }
    if (hi - lo < 0.1) {
      range_reason = "the gripper command never changes; a log that opens and closes the gripper would decide";
    } else if (lo < -0.05) {
      range = GripperRange::kSymmetric;
      range_conf = 1.0;
    } else if (hi <= 1.05 && n_lo > 0 && n_hi > 0 && static_cast<double>(n_ends) >= 0.95 * static_cast<double>(n_all)) {
      // binary commands at 0 and 1 only: a [0, 1] convention (a [-1, 1] policy would close at -1)
      range = GripperRange::kUnit;
      range_conf = 1.0;
    } else if (hi <= 1.05) {
      // continuous commands inside [0, 1] fit either range (a [-1, 1] policy that never closes fully,
      // a learned policy's clipped outputs): the log cannot tell, and claims nothing
      range_checked = false;
      range_reason = "the gripper commands stay inside [0, 1] and take values between the ends: either range fits them; commands "
                     "below 0, or only 0 and 1, would decide";
    } else {
      range_reason = "the gripper commands do not reach both ends of either range";
    }
    // polarity: the fingers after the step against the (lagged) gripper command, the slope's sign with
    // a jackknife over the log's units (finger positions are slow and serially correlated: a count of
    // samples overstates the evidence, and on shuffled actions named a polarity at confidence 1). With
    // the lag not resolved the sign must agree, and pass, at every lag of the grammar.
    const GripperRange r_used = range_conf > 0 ? range : o.declared.gripper_range;
    const int U = detail::units_of(eps);
    struct Sums {
      double sx{0}, sy{0}, sxx{0}, sxy{0}, syy{0}, m{0};
      void add(double x, double y) {
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        m += 1;
      }
      void sub(const Sums& o) {
        sx -= o.sx;
        sy -= o.sy;
        sxx -= o.sxx;
        sxy -= o.sxy;
        syy -= o.syy;
        m -= o.m;
      }
      double vx() const { return m > 0 ? sxx - sx * sx / m : 0.0; }
      double vy() const { return m > 0 ? syy - sy * sy / m : 0.0; }
      double slope() const { return vx() > 0 ? (sxy - sx * sy / m) / vx() : 0.0; }
    };
    const auto slope_t = [&](int lag, Sums* total) {
      std::vector<Sums> unit(static_cast<std::size_t>(U));
      Sums all;
      for (const auto& ep : eps)
        for (std::size_t t = 0; t < ep.size(); ++t) {
          if (!ep[t].finger_next || t < static_cast<std::size_t>(lag)) continue;
          double g = ep[t - static_cast<std::size_t>(lag)].raw[kGripper];
          if (r_used == GripperRange::kUnit) g = 2 * g - 1;
          unit[static_cast<std::size_t>(ep[t].unit)].add(g, *ep[t].finger_next);
          all.add(g, *ep[t].finger_next);
        }
      *total = all;
      std::vector<double> loo;
      for (const auto& u : unit) {
        if (u.m == 0) continue;
        Sums rest = all;
        rest.sub(u);
        if (rest.vx() <= 0) return 0.0;  // one unit holds every change of the command
        loo.push_back(rest.slope());
      }
      if (loo.size() < 2) return 0.0;
      double mean = 0, ss = 0;
      for (double x : loo) mean += x / static_cast<double>(loo.size());
      for (double x : loo) ss += (x - mean) * (x - mean);
      const double se = std::sqrt(ss * static_cast<double>(loo.size() - 1) / static_cast<double>(loo.size()));
      const double b = all.slope();
      return se > 0 ? b / se : 0.0;
    };
    Sums total;
    slope_t(map_lag, &total);
    if (total.m < 3) {
      polarity_checked = false;
      polarity_reason = "the log has no finger positions: the gripper's polarity shows only in the fingers";
    } else {
      const double finger_sd = std::sqrt(std::max(total.vy(), 0.0) / total.m);
      if (total.vx() <= 1e-12 * total.m) {
        polarity_reason = "the gripper command never changes; a log that opens and closes the gripper would decide";
      } else if (finger_sd < 1e-5) {
        // fingers that never move carry no polarity (a zero slope over a zero standard error is no evidence)
        polarity_checked = false;
        polarity_reason = "the finger positions never move in the log (SD " + fmt("%.2g", finger_sd) +
                          " m): they carry no polarity; a log whose fingers follow the gripper would decide";
      } else {
        std::vector<int> lags;
        if (commands && ev.lag_resolved) lags.push_back(map_lag);
        else lags.assign(grammar::kLagGrid.begin(), grammar::kLagGrid.end());
        double weakest = std::numeric_limits<double>::infinity(), best_r2 = 0;
        int sign = 0;
        bool agree = true;
        for (int lag : lags) {
          Sums at;
          const double t = slope_t(lag, &at);
          const double cov = at.sxy - at.sx * at.sy / std::max(at.m, 1.0);
          if (at.vx() > 0 && at.vy() > 0) best_r2 = std::max(best_r2, cov * cov / (at.vx() * at.vy()));
          const int sg = t > 0 ? 1 : (t < 0 ? -1 : 0);
          if (sign == 0) sign = sg;
          agree = agree && sg != 0 && sg == sign;
          weakest = std::min(weakest, std::abs(t));
        }
        const double tc = ev.t_critical > 0 ? ev.t_critical : 3.0;
        const double zf = floor >= 1.0 ? 40.0 : detail::normal_quantile(floor);
        inverted = sign < 0;
        // the grammar's gripper sets the fingers' target: they follow the command closely (R² well above
        // a half); fingers that mostly move otherwise (contacts, a cube between them) carry a polarity
        // only by accident
        polarity_conf = agree && weakest >= tc && best_r2 >= kMinFingerR2 ? std::max(floor, normal_cdf(std::min(weakest, 1e6) * zf / tc)) : 0.0;
        if (polarity_conf < floor)
          polarity_reason = "the fingers follow the gripper command too weakly or inconsistently over the log's parts (t = " +
                            fmt("%.2f", agree ? weakest : 0.0) + ", " + fmt("%.2f", tc) + " needed; the command explains " +
                            fmt("%.0f", 100 * best_r2) + " % of the finger positions, " + fmt("%.0f", 100 * kMinFingerR2) +
                            " % needed); more open and close commands would decide";
      }
    }
  } else {
    range_reason = "the log has no gripper channel";
    polarity_reason = "the log has no gripper channel";
  }

  // 5. the identified conventions
  Conventions id = o.declared;
  id.action = kind_decidable ? kind : o.declared.action;
  {
    auto f = map.fields();
    f.gripper_inverted = polarity_checked && polarity_conf > 0 ? inverted : o.declared.contract.gripper_inverted();
    map = Contract::make(f);
    id.contract = map;
  }
  if (commands)
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      R.effective_gain[ii] = alpha[ii] * ev.map_sign[ii] * ev.map_gain[ii];
      if (!o.model) R.alpha[ii] = ev.map_gain[ii];
      else R.alpha[ii] = alpha[ii];
    }
  id.gripper_range = range_conf > 0 ? range : o.declared.gripper_range;
  std::array<double, 3> rep_p{1.0 / 3, 1.0 / 3, 1.0 / 3};
  double rep_separation = 0, rep_t = 0;
  if (commands) {
    std::array<std::array<double, 3>, 3> sq{};
    // the replay of the rotation channels at the log's own gains (working units of alpha)
    auto rf = map.fields();
    for (int i = 0; i < kPoseDim; ++i) rf.scale[static_cast<std::size_t>(i)] = std::max(ev.map_gain[static_cast<std::size_t>(i)], 1e-9);
    std::vector<std::array<double, 3>> unit_sse;
    rep_p = rotation_rep_posterior(eps, alpha, sigma_n, Contract::make(rf), &rep_separation, &sq, &unit_sse);
    int best = 0;
    for (int r = 1; r < 3; ++r)
      if (rep_p[static_cast<std::size_t>(r)] > rep_p[static_cast<std::size_t>(best)]) best = r;
    // the representation is told apart only if it predicts better unit by unit (a paired t over the
    // log's parts, as the hypotheses): the Gaussian likelihood alone ignores serially correlated
    // residuals, and on the simulator's learned-policy logs named Euler angles at 5,000 transitions
    rep_t = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 3; ++r) {
      if (r == best) continue;
      std::vector<double> a, b;
      for (const auto& u : unit_sse) {
        a.push_back(u[static_cast<std::size_t>(best)]);
        b.push_back(u[static_cast<std::size_t>(r)]);
      }
      rep_t = std::min(rep_t, detail::paired_t(a, b, o.min_margin));
    }
    id.rotation = static_cast<RotationRep>(best);
    // the misspecification ratio with the rotation channels under the identified representation (the
    // linear fit has the other representations' second-order terms in its residual)
    if (o.model) {
      double ratio = 0;
      for (int c = 0; c < kPoseDim; ++c) {
        const auto cc = static_cast<std::size_t>(c);
        const double s = o.model->sigma[cc] / std::abs(alpha[cc]);
        double rms = ev.residual_rms[cc];
        if (c >= 3 && R.committed_sign[3] != 0 && R.committed_sign[4] != 0 && R.committed_sign[5] != 0)
          rms = std::min(rms, std::sqrt(sq[static_cast<std::size_t>(best)][cc - 3] / static_cast<double>(R.transitions)) / std::abs(alpha[cc]));
        ratio += std::pow(rms / s, 2) / kPoseDim;
      }
      R.fit_ratio = ratio;
    }
  }
  R.identified = id;

  // 6. the fields
  const Contract& dc = o.declared.contract;
  const std::string not_commands =
      kind_decidable ? "the logged actions are poses, not commands of the grammar"
                     : "the TCP does not move in the log: nothing responds to the commands";
  const std::string no_evidence =
      "the logged actions do not explain the logged motion: under every hypothesis searched, a fit that leaves out one "
      "episode predicts it no better than ignoring the actions (paired t = " + fmt("%.2f", ev.null_t) + ", " +
      fmt("%.2f", ev.t_critical) + " needed); check that actions and poses are aligned row by row";
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
    // the confidence of a per-channel field is its weakest resolved channel's (0 when none is)
    double weakest = 1.0;
    bool any = false;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      if (conf[ii] < floor) {
        a.unresolved_channels.push_back(i);
      } else {
        weakest = std::min(weakest, conf[ii]);
        any = true;
      }
    }
    a.confidence = any ? weakest : 0.0;
    a.resolved = a.unresolved_channels.empty();
    std::vector<std::string> parts, diffs;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      const bool ok = conf[ii] >= floor;
      std::string v, dv;
      if (f == Field::kPermutation) {
        v = std::to_string(map.permutation()[ii]);
        dv = std::to_string(dc.permutation()[ii]);
      } else {
        v = std::to_string(map.sign()[ii]);
        dv = std::to_string(dc.sign()[ii]);
      }
      parts.push_back(ok ? v : "?");
      if (ok && v != dv) {
        if (f == Field::kPermutation)
          diffs.push_back("output channel " + std::to_string(i) + " (" + kChannel[i] + ") reads raw channel " + v + ", declared " + dv);
        else
          diffs.push_back("channel " + std::to_string(i) + " (" + kChannel[i] + ") sign FLIPPED");
      }
    }
    a.identified = "(" + join(parts, ", ") + ")";
    a.diff = a.resolved ? diff_sentence(dc, map, f) : join(diffs, "; ");
    if (a.resolved && a.diff.empty()) a.diff = join(diffs, "; ");
    if (!a.resolved) {
      std::vector<std::string> why;
      for (int i : a.unresolved_channels) {
        const auto& c = ev.channel[static_cast<std::size_t>(i)];
        std::string w = f == Field::kSign && c.routed && !c.sign_committed ? c.why : c.why;
        if (w.empty()) w = "its routing is not committed";
        why.push_back(std::string(kChannel[i]) + ": " + w);
      }
      a.reason = "not resolved on output channel(s) " + channel_list(a.unresolved_channels) + " (" + join(why, "; ") +
                 "); a log that commands every channel, positive and negative, on its own and in reversals, would decide";
      if (!ev.frame_resolved)
        a.reason += "; with the TCP orientation nearly constant, a tool-frame contract equals a base-frame one with other signs and channels, so also rotate the TCP";
    }
    return a;
  };
  if (commands && !ev.evidence) {
    perm_conf.fill(0.0);
    sign_conf.fill(0.0);
  }
  R.fields.push_back(per_channel(Field::kPermutation, perm_conf));
  R.fields.push_back(per_channel(Field::kSign, sign_conf));
  {
    AuditField s;
    s.name = "scale";
    s.declared = field_value(dc, Field::kScale);
    if (!commands) {
      s.checked = false;
      s.identified = s.declared;
      s.reason = not_commands;
    } else if (!o.model) {
      s.checked = false;
      std::vector<std::string> g;
      for (double x : ev.map_gain) g.push_back(fmt("%.3g", x));
      s.identified = "(" + join(g, ", ") + ")";
      s.reason = "scale unchecked: without a response calibration (--task or --calibration) a log cannot separate the "
                 "contract's scale from the robot's response gain; the identified values are the log's gains per unit command";
    } else {
      // The calibrated gain describes the calibration's motion (random walks); a log's motion runs at
      // another gain (sustained commands, saturation, contacts), so a channel's scale is only known to
      // lie in a band: the log's gain / calibrated gain within the gain tolerance, widened by two
      // jackknife standard errors. The declaration agrees if its scale is in that band and differs if
      // it is outside; the band is what is reported, never the nearest grid scale.
      std::vector<std::string> parts, diffs;
      s.confidence = 1.0;
      bool any = false;
      for (int i = 0; i < kPoseDim; ++i) {
        const auto ii = static_cast<std::size_t>(i);
        const auto& c = ev.channel[ii];
        const double g = c.gain, se = c.gain_se;
        const double lo = std::max(g / o.gain_tolerance - 2 * se, 0.0), hi = g * o.gain_tolerance + 2 * se;
        R.scale_band[ii] = {lo, hi};
        bool on_grid = false;
        for (double k : grammar::kScaleGrid) on_grid = on_grid || (k >= lo && k <= hi);
        const bool ok = ev.evidence && c.sign_committed && std::isfinite(hi);
        if (!ok) {
          s.unresolved_channels.push_back(i);
          parts.push_back("?");
          continue;
        }
        any = true;
        R.scale_committed[ii] = true;
        const std::string band = "[" + fmt("%.2g", lo) + ", " + fmt("%.2g", hi) + "]";
        parts.push_back(on_grid ? band : "~" + fmt("%.2g", g) + " (outside the grammar)");
        const double dk = dc.scale()[ii];
        if (!(dk >= lo && dk <= hi))
          diffs.push_back("channel " + std::to_string(i) + " (" + kChannel[i] + ") scale " + python_float_repr(dk) + " is outside the log's band " + band +
                          " (its gain is " + fmt("%.2f", g) + "x the calibrated one" + (on_grid ? "" : "; no scale of the grammar is in the band") + ")");
      }
      s.confidence = any ? floor : 0.0;
      s.identified = "(" + join(parts, ", ") + ")";
      s.resolved = s.unresolved_channels.empty();
      s.diff = join(diffs, "; ");
      if (!s.resolved)
        s.reason = "not resolved on output channel(s) " + channel_list(s.unresolved_channels) +
                   ": their routing and sign are not committed; longer motion on those channels would decide";
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
  // which modes the log cannot exclude, in words (for the reasons)
  const auto rivals = [&](auto differs) {
    std::vector<std::string> v;
    for (std::size_t k = 0; k < ev.modes.size(); ++k)
      if (ev.plausible[k] && differs(ev.modes[k])) v.push_back(std::string(to_string(ev.modes[k].target)) + "/" + (ev.modes[k].frame ? "tool" : "base") + "/lag " + std::to_string(ev.modes[k].lag));
    if (v.size() > 4) {
      const auto n = v.size();
      v.resize(4);
      v.push_back("... (" + std::to_string(n) + " in all)");
    }
    return join(v, ", ");
  };
  const detail::Mode bm = commands ? ev.modes[static_cast<std::size_t>(ev.best)] : detail::Mode{};
  const std::string unresolved_prefix = commands && !ev.evidence ? no_evidence : "";
  // a scalar field's confidence: its weakest paired t mapped so that the test's threshold is the floor
  const auto conf_of = [&](bool resolved, double t) {
    if (!(commands && ev.evidence && resolved)) return 0.0;
    const double z = floor >= 1.0 ? 40.0 : detail::normal_quantile(floor);
    return std::max(floor, normal_cdf(std::min(t, 1e6) * z / ev.t_critical));
  };
  R.fields.push_back(scalar("target", to_string(dc.target()), commands ? to_string(map.target()) : to_string(dc.target()),
                            conf_of(ev.target_resolved, ev.target_t), commands,
                            !commands ? not_commands
                            : !ev.evidence ? no_evidence
                                           : "delta and absolute targets are not told apart (the log cannot exclude " +
                                                 rivals([&](const detail::Mode& m) { return m.target != bm.target; }) +
                                                 "); commands that change from step to step (reversals) would decide",
                            "target encoding differs: declared " + std::string(to_string(dc.target())) + ", the log is " + to_string(map.target())));
  double spread = 0;
  for (const auto& ep : eps)
    for (const auto& s : ep) spread = std::max(spread, Eigen::AngleAxisd(eps.front().front().R.transpose() * s.R).angle());
  R.fields.push_back(scalar("frame", to_string(dc.frame()), commands ? to_string(map.frame()) : to_string(dc.frame()),
                            conf_of(ev.frame_resolved, ev.frame_t), commands,
                            !commands ? not_commands
                            : !ev.evidence ? no_evidence
                                           : "base and tool frames are not told apart (the TCP orientation varies by " + fmt("%.2f", spread) +
                                                 " rad over the log); a log in which the TCP turns by at least " + fmt("%.1f", std::max(o.min_rotation_spread, 0.2)) +
                                                 " rad while translating would decide",
                            "reference frame differs: declared " + std::string(to_string(dc.frame())) + ", the log is " + to_string(map.frame())));
  {
    bool on_grid = false;
    for (int g : grammar::kLagGrid) on_grid = on_grid || map.lag() == g;
    const std::string lag_text = std::to_string(map.lag()) + (commands && !on_grid ? " (outside the grammar)" : "");
    const std::string declared_text = std::to_string(dc.lag()) + (std::find(grammar::kLagGrid.begin(), grammar::kLagGrid.end(), dc.lag()) == grammar::kLagGrid.end() ? " (outside the grammar)" : "");
    R.fields.push_back(scalar("lag", declared_text, commands ? lag_text : declared_text, conf_of(ev.lag_resolved, ev.lag_t), commands,
                              !commands ? not_commands
                              : !ev.evidence ? no_evidence
                                             : "the actuation lag is not resolved (the log cannot exclude " +
                                                   rivals([&](const detail::Mode& m) { return m.lag != bm.lag; }) +
                                                   "); commands that change abruptly (steps, reversals) would decide",
                              "actuation lag differs: declared " + std::to_string(dc.lag()) + " step(s), the log shows " + std::to_string(map.lag()) +
                                  " step(s)" + (on_grid ? "" : ", outside the grammar's lags {0, 1, 2, 4}")));
  }
  (void)unresolved_prefix;
  const auto grip_words = [](bool inv) { return std::string(inv ? "inverted (+1 closes)" : "not inverted (+1 opens)"); };
  R.fields.push_back(scalar("gripper_inverted", grip_words(dc.gripper_inverted()), grip_words(id.contract.gripper_inverted()),
                            polarity_conf, polarity_checked, polarity_reason,
                            "gripper polarity differs: declared " + grip_words(dc.gripper_inverted()) + ", the fingers show " +
                                grip_words(id.contract.gripper_inverted())));
  R.fields.push_back(scalar("gripper_range", to_string(o.declared.gripper_range), to_string(id.gripper_range), range_conf, range_checked,
                            range_reason,
                            "gripper range differs: declared " + std::string(to_string(o.declared.gripper_range)) + ", the logged gripper commands span " +
                                to_string(id.gripper_range)));
  {
    const double zf = floor >= 1.0 ? 40.0 : detail::normal_quantile(floor);
    const double conf = rep_t >= ev.t_critical ? std::max(floor, normal_cdf(std::min(rep_t, 1e6) * zf / ev.t_critical)) : 0.0;
    // the representations differ at second order only (half the cross products of the angles): when even
    // a perfect fit could not reach the floor (expected log-odds below log(floor / (1 - floor))), the
    // log cannot tell them apart, and the field is not checked rather than unresolved
    const double needed = 2.0 * std::log(std::max(floor, 0.5) / std::max(1.0 - floor, 1e-12));
    // checked only where the rotation channels' routing and sign are committed (the replay needs them)
    bool rot_committed = true;
    for (int c = 3; c < kPoseDim; ++c) rot_committed = rot_committed && R.committed_sign[static_cast<std::size_t>(c)] != 0;
    const bool rep_checkable = commands && ev.evidence && rot_committed && rep_separation >= needed && rep_t >= ev.t_critical;
    R.fields.push_back(scalar("rotation", to_string(o.declared.rotation), rep_checkable ? to_string(id.rotation) : to_string(o.declared.rotation),
                              rep_checkable ? conf : 0.0, rep_checkable,
                              commands ? "the log cannot tell the rotation representations apart: they differ only at second order (half the cross products "
                                         "of the angles), and the log's rotations separate them by " + fmt("%.2g", rep_separation) + " (squared noise units; " +
                                         fmt("%.2g", needed) + " needed), and over the log's parts the best one predicts better at paired t = " +
                                         fmt("%.2f", rep_t) + " (" + fmt("%.2f", ev.t_critical) + " needed); simultaneous rotation commands on two or more axes, well above the noise, would decide"
                                       : not_commands,
                              "rotation representation differs: declared " + describe(o.declared.rotation) + ", the log's rotation deltas are " +
                                  describe(id.rotation)));
  }
  R.fields.push_back(scalar("action", to_string(o.declared.action), to_string(id.action), kind_conf, true,
                            "the TCP does not move in the log, so the actions cannot be compared with the poses",
                            "the logged action differs: declared " + action_words(o.declared.action) + ", the log's action is " + action_words(id.action)));
  if (commands && ev.evidence) {
    if (ev.target_resolved) R.committed_target = to_string(map.target());
    if (ev.frame_resolved) R.committed_frame = to_string(map.frame());
    if (ev.lag_resolved) R.committed_lag = map.lag();
  }
  if (const AuditField* g = R.field("gripper_inverted"); g && g->checked && g->resolved) R.committed_gripper_inverted = id.contract.gripper_inverted();

  // 7. the verdict
  std::vector<std::string> diffs, unresolved, unchecked;
  for (const auto& f : R.fields) {
    if (!f.checked) {
      if (f.name != "gripper_range") unchecked.push_back(f.name);
      continue;
    }
    if (!f.diff.empty()) diffs.push_back(f.diff);
    if (!f.resolved) {
      if (f.unresolved_channels.empty() || f.unresolved_channels.size() == static_cast<std::size_t>(kPoseDim))
        unresolved.push_back(f.name);
      else
        unresolved.push_back(f.name + " on channel(s) " + channel_list(f.unresolved_channels));
    }
  }
  if (commands && !ev.evidence) {
    R.status = Status::kInconclusive;
    R.reason = "no evidence: " + no_evidence + ". Abstaining.";
  } else if (commands && o.model && R.fit_ratio > o.misspec_ratio) {
    R.status = Status::kInconclusive;
    R.reason = "response misspecification: the best hypothesis fits the log at " + fmt("%.1f", R.fit_ratio) +
               "x the calibrated noise variance (threshold " + fmt("%.1f", o.misspec_ratio) +
               "x): the log's controller or response is outside what the grammar and calibration describe. Abstaining.";
  } else if (!diffs.empty()) {
    R.status = Status::kMismatch;
    R.reason = join(diffs, "; ");
    if (!unresolved.empty()) R.reason += " (not decided by this log, and not part of this verdict: " + join(unresolved, "; ") + ")";
  } else if (!unresolved.empty()) {
    R.status = Status::kInconclusive;
    R.reason = "the log does not decide " + join(unresolved, "; ") + "; what it decides agrees with the declaration. Abstaining rather than guessing.";
  } else {
    R.status = Status::kPass;
    R.reason = "every checked field resolved and agrees with the declaration";
    if (!unchecked.empty()) R.reason += "; the log cannot check " + join(unchecked, ", ") + " (see below)";
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
  j["fit_ratio"] = r.fit_ratio;
  j["noise_inflation"] = r.noise_inflation;
  j["model_fitted"] = r.model_fitted;
  j["alpha"] = r.alpha;
  j["effective_gain"] = r.effective_gain;
  j["scale_band"] = r.scale_band;
  j["excitation"] = r.excitation;
  j["episodes"] = r.episodes;
  j["transitions"] = r.transitions;
  j["outlier_rows"] = r.outlier_rows;
  j["evidence_t"] = r.evidence_t;
  j["t_critical"] = r.t_critical;
  j["plausible_hypotheses"] = r.plausible_modes;
  {
    // what the verdict commits to, per field (null: not committed), for programs that score audits
    nlohmann::json c;
    c["permutation"] = nlohmann::json::array();
    c["sign"] = nlohmann::json::array();
    c["scale_band"] = nlohmann::json::array();
    for (std::size_t i = 0; i < static_cast<std::size_t>(kPoseDim); ++i) {
      c["permutation"].push_back(r.committed_raw[i] >= 0 ? nlohmann::json(r.committed_raw[i]) : nlohmann::json());
      c["sign"].push_back(r.committed_sign[i] != 0 ? nlohmann::json(r.committed_sign[i]) : nlohmann::json());
      c["scale_band"].push_back(r.scale_committed[i] ? nlohmann::json(r.scale_band[i]) : nlohmann::json());
    }
    c["target"] = r.committed_target ? nlohmann::json(*r.committed_target) : nlohmann::json();
    c["frame"] = r.committed_frame ? nlohmann::json(*r.committed_frame) : nlohmann::json();
    c["lag"] = r.committed_lag ? nlohmann::json(*r.committed_lag) : nlohmann::json();
    c["gripper_inverted"] = r.committed_gripper_inverted ? nlohmann::json(*r.committed_gripper_inverted) : nlohmann::json();
    j["committed"] = c;
  }
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
  s << "\nBest hypothesis (only the resolved fields above are claimed): " << r.identified.contract.to_json() << "\n";
  s << "Gain per output channel (response per unit command" << (r.model_fitted ? ", physical units" : ", x the calibrated gain") << "):";
  for (double g : r.effective_gain) s << " " << fmt("%.4g", g);
  s << "\nEvidence: the actions explain the motion at paired t = " << fmt("%.2f", r.evidence_t) << " (threshold " << fmt("%.2f", r.t_critical)
    << "); " << r.plausible_modes << " of the searched (target, frame, lag) hypotheses not excluded; " << r.outlier_rows << " row(s) left out as outliers";
  if (!r.model_fitted) s << "; fit " << fmt("%.2f", r.fit_ratio) << "x the calibrated noise variance";
  s << "\n";
  s << "Command RMS per raw channel:";
  for (double g : r.excitation) s << " " << fmt("%.3f", g);
  s << "\n";
  return s.str();
}

}  // namespace actionshift::selftest
