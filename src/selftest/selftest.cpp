#include "actionshift/selftest/selftest.hpp"

#include "actionshift/core/decoder.hpp"
#include "actionshift/core/transforms.hpp"
#include "actionshift/selftest/library.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace actionshift::selftest {

const char* to_string(Strategy s) { return s == Strategy::kFixed ? "fixed" : "entropy"; }

namespace {

constexpr int kMaxBudget = 10000;

std::string num(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

bool fail(std::string* err, const std::string& msg) {
  if (err) *err = "selftest options: " + msg;
  return false;
}

bool check_pose(const TcpPose& p, const char* what, std::string* err) {
  if (!p.position.allFinite() || !p.quaternion.allFinite()) {
    if (err) *err = std::string("selftest: ") + what + ": TCP pose must be finite";
    return false;
  }
  if (p.quaternion.norm() < 1e-9) {
    if (err) *err = std::string("selftest: ") + what + ": TCP quaternion must be non-zero (w x y z)";
    return false;
  }
  if (p.fingers && !p.fingers->allFinite()) {
    if (err) *err = std::string("selftest: ") + what + ": finger positions must be finite";
    return false;
  }
  // metres: a pose beyond this is a unit or wiring error, and its squares would overflow the belief
  constexpr double kMaxCoordinate = 1e6;
  if (p.position.cwiseAbs().maxCoeff() > kMaxCoordinate || (p.fingers && p.fingers->cwiseAbs().maxCoeff() > kMaxCoordinate)) {
    if (err) *err = std::string("selftest: ") + what + ": TCP or finger position beyond 1e6 m (check the units)";
    return false;
  }
  return true;
}

// rotation angle of a (w x y z) quaternion from identity [rad]
double angle_from_identity(const Eigen::Vector4d& q) {
  return 2.0 * std::acos(std::clamp(std::abs(q[0]) / q.norm(), 0.0, 1.0));
}

// the field a hypothesis shares with the MAP
bool same_field(const Contract& a, const Contract& b, Field f) {
  switch (f) {
    case Field::kPermutation: return a.permutation() == b.permutation();
    case Field::kSign: return a.sign() == b.sign();
    case Field::kScale: return a.scale() == b.scale();
    case Field::kTarget: return a.target() == b.target();
    case Field::kFrame: return a.frame() == b.frame();
    default: return a.lag() == b.lag();
  }
}

}  // namespace

bool validate(const Options& o, std::string* err) noexcept {
  if (o.budget < 1 || o.budget > kMaxBudget)
    return fail(err, "budget must be in [1, " + std::to_string(kMaxBudget) + "] (got " + std::to_string(o.budget) + ")");
  if (!(o.amplitude > 0.0 && o.amplitude <= 1.0))
    return fail(err, "amplitude must be in (0, 1] (got " + num(o.amplitude) + ")");
  if (!(o.confidence_floor > 0.0 && o.confidence_floor <= 1.0))
    return fail(err, "confidence_floor must be in (0, 1] (got " + num(o.confidence_floor) + ")");
  if (!(o.misspec_ratio > 0.0) || !std::isfinite(o.misspec_ratio))
    return fail(err, "misspec_ratio must be finite and positive (got " + num(o.misspec_ratio) + ")");
  if (o.misspec_ratio_absolute && (!(*o.misspec_ratio_absolute > 0.0) || !std::isfinite(*o.misspec_ratio_absolute)))
    return fail(err, "misspec_ratio_absolute must be finite and positive (got " + num(*o.misspec_ratio_absolute) + ")");
  if (!(o.min_frame_angle >= 0.0) || !std::isfinite(o.min_frame_angle))
    return fail(err, "min_frame_angle must be finite and nonnegative (got " + num(o.min_frame_angle) + ")");
  if (o.strategy != Strategy::kFixed && o.strategy != Strategy::kEntropy) return fail(err, "strategy must be fixed or entropy");
  if (o.gripper && (!std::isfinite(o.gripper->offset) || !std::isfinite(o.gripper->gain) || o.gripper->gain == 0.0))
    return fail(err, "gripper.offset must be finite and gripper.gain finite and non-zero (got " + num(o.gripper->offset) +
                         ", " + num(o.gripper->gain) + ")");
  for (int c = 0; c < kPoseDim; ++c) {
    const auto k = static_cast<std::size_t>(c);
    if (!std::isfinite(o.model.alpha[k]) || o.model.alpha[k] == 0.0)
      return fail(err, "model.alpha[" + std::to_string(c) + "] must be finite and non-zero (got " + num(o.model.alpha[k]) + ")");
    if (!std::isfinite(o.model.sigma[k]) || o.model.sigma[k] <= 0.0)
      return fail(err, "model.sigma[" + std::to_string(c) + "] must be finite and positive (got " + num(o.model.sigma[k]) + ")");
  }
  return true;
}

struct SelfTest::Impl {
  Impl(const Options& o, std::vector<Contract> declared)
      : opt(o), pool(std::move(declared)), belief(pool, o.model), candidates(adapt::probe_candidates(o.amplitude)) {
    preview.budget = o.budget;
    preview.amplitude = o.amplitude;
    // the self-test previews as the project's `calibrated` variant does (docs/adapters.md): α-scaled,
    // through each hypothesis's lag FIFO; the benchmark's methods default to the paper's rule instead
    preview.calibrated_preview = true;
    preview.lag_aware_preview = true;
  }

  // the next probe: fixed pulses, or the entropy-minimising axis pulse among the admissible ones:
  // - return balancing: a channel whose commanded raw sum is non-zero may only be pulsed back to zero;
  // - no saturation: no hypothesis holding posterior mass may decode the pulse beyond the controller's
  //   clip range (|translation_i| <= 1, |rotation| <= 1, docs/semantics.md §1), which the response model does not
  //   describe (an absolute-target wiring turns +a then −a on one channel into a 2·scale·a step).
  // if nothing is admissible the balance rule alone decides
  Action choose(const Mat3& R) const {
    const int step = static_cast<int>(raws.size());
    if (opt.strategy == Strategy::kFixed) return adapt::fixed_probe_pulse(step, opt.amplitude);
    const std::vector<double> eh = adapt::expected_posterior_entropy(belief, candidates, R, preview);
    const Eigen::VectorXd p = belief.probs();
    std::vector<Action> preds;
    std::size_t best = candidates.size(), fallback = candidates.size();
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      if (opt.return_balanced) {
        const int ch = static_cast<int>(i % kPoseDim);
        if (std::abs(raw_sum[ch] + candidates[i][ch]) > opt.amplitude * (1.0 + 1e-12)) continue;
      }
      if (fallback == candidates.size() || eh[i] < eh[fallback]) fallback = i;
      belief.preview(candidates[i], R, /*lag_aware=*/true, preds);
      bool saturates = false;
      for (int h = 0; h < belief.size() && !saturates; ++h) {
        if (p[h] < kPlausible) continue;
        const Action& c = preds[static_cast<std::size_t>(h)];
        saturates = c.head<3>().cwiseAbs().maxCoeff() > 1.0 + 1e-9 || c.segment<3>(3).norm() > 1.0 + 1e-9;
      }
      if (saturates) continue;
      if (best == candidates.size() || eh[i] < eh[best]) best = i;
    }
    return candidates[best < candidates.size() ? best : fallback];
  }
  static constexpr double kPlausible = 1e-4;  // posterior mass below which a hypothesis may saturate

  Mat3 rotation_of(const TcpPose& p) const {
    if (opt.frame_rotation == FrameRotation::kIdentity) return Mat3::Identity();
    return quat_wxyz_to_matrix(p.quaternion);
  }

  Options opt;
  std::vector<Contract> pool;
  adapt::PoolBelief belief;
  std::vector<Action> candidates;  // +a·e0 … +a·e5, −a·e0 … −a·e5
  adapt::ProbeOptions preview;
  Pose6 raw_sum{Pose6::Zero()};    // commanded raw pose sum since begin()

  bool started{false};
  TcpPose start, last;
  std::optional<Action> pending;  // sent, not yet observed
  Mat3 pending_R{Mat3::Identity()};
  std::vector<Action> raws;       // observed probes
  std::vector<Mat3> rotations;    // R used for each
  std::vector<Pose6> responses;   // measured TCP response to each
  double path{0}, excursion{0}, turned{0}, fingers{0};
  bool have_fingers{true};
  std::optional<double> gripper_hold;  // raw gripper command of every probe (Options::gripper), else 0
  double min_angle{std::numeric_limits<double>::infinity()};
};

SelfTest::SelfTest(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

SelfTest::SelfTest(const Options& o) {
  std::string err;
  if (!validate(o, &err)) throw std::invalid_argument(err);
  auto pool = o.pool.empty() ? default_pool(o.expected) : with_expected(o.pool, o.expected);
  impl_ = std::make_unique<Impl>(o, std::move(pool));
}

std::optional<SelfTest> SelfTest::create(const Options& o, std::string* err) noexcept {
  if (!validate(o, err)) return std::nullopt;
  try {
    return SelfTest(o);
  } catch (const std::exception& e) {  // allocation failure: reported, not swallowed
    if (err) *err = std::string("selftest: ") + e.what();
    return std::nullopt;
  }
}

SelfTest::SelfTest(SelfTest&&) noexcept = default;
SelfTest& SelfTest::operator=(SelfTest&&) noexcept = default;
SelfTest::~SelfTest() = default;

bool SelfTest::try_begin(const TcpPose& p, std::string* err) noexcept {
  if (!check_pose(p, "begin", err)) return false;
  auto& s = *impl_;
  s.belief.reset();
  s.raw_sum.setZero();
  s.started = true;
  s.start = s.last = p;
  s.pending.reset();
  s.raws.clear();
  s.rotations.clear();
  s.responses.clear();
  s.path = s.excursion = s.turned = s.fingers = 0;
  s.have_fingers = p.fingers.has_value();
  s.gripper_hold.reset();
  if (s.opt.gripper && p.fingers) {  // the command whose finger target is where the fingers are now
    const double g = std::clamp((p.fingers->mean() - s.opt.gripper->offset) / s.opt.gripper->gain, -1.0, 1.0);
    s.gripper_hold = s.opt.expected.gripper_inverted() ? -g : g;  // raw, under the expected wiring
  }
  s.min_angle = std::numeric_limits<double>::infinity();
  return true;
}

void SelfTest::begin(const TcpPose& p) {
  std::string err;
  if (!try_begin(p, &err)) throw std::invalid_argument(err);
}

std::optional<Action> SelfTest::next_probe() {
  auto& s = *impl_;
  if (!s.started) throw std::logic_error("selftest: next_probe() before begin()");
  if (s.pending) return s.pending;
  if (static_cast<int>(s.raws.size()) >= s.opt.budget) return std::nullopt;
  s.pending_R = s.rotation_of(s.last);
  Action raw = s.choose(s.pending_R);
  // the probe bound is a promise to the caller's hardware: enforce it, whatever the strategy did
  for (int c = 0; c < kPoseDim; ++c) raw[c] = std::clamp(raw[c], -s.opt.amplitude, s.opt.amplitude);
  raw[kGripper] = s.gripper_hold.value_or(0.0);
  s.pending = raw;
  return raw;
}

bool SelfTest::try_observe(const TcpPose& p, std::string* err) noexcept {
  auto& s = *impl_;
  if (!s.pending) {
    if (err) *err = "selftest: observe() without an outstanding probe (call next_probe() first)";
    return false;
  }
  if (!check_pose(p, "observe", err)) return false;

  // response = [translation, rotation vector of q_cur ⊗ conj(q_prev)] (adapt::tcp_response)
  Pose6 response;
  response.head<3>() = p.position - s.last.position;
  Eigen::Vector4d conj = s.last.quaternion;
  conj.tail<3>() *= -1.0;
  response.tail<3>() = adapt::quat_to_rotvec(adapt::quat_multiply(p.quaternion, conj));

  s.belief.update(*s.pending, response, s.pending_R);
  s.raw_sum += s.pending->head<kPoseDim>();
  s.raws.push_back(*s.pending);
  s.rotations.push_back(s.pending_R);
  s.responses.push_back(response);
  s.min_angle = std::min(s.min_angle, angle_from_identity(s.last.quaternion));
  s.path += response.head<3>().norm();
  s.turned += response.tail<3>().norm();
  s.excursion = std::max(s.excursion, (p.position - s.start.position).norm());
  if (s.have_fingers && p.fingers && s.last.fingers) s.fingers += (*p.fingers - *s.last.fingers).cwiseAbs().sum();
  else s.have_fingers = false;
  s.last = p;
  s.pending.reset();
  return true;
}

void SelfTest::observe(const TcpPose& p) {
  if (!impl_->pending) throw std::logic_error("selftest: observe() without an outstanding probe (call next_probe() first)");
  std::string err;
  if (!try_observe(p, &err)) throw std::invalid_argument(err);
}

bool SelfTest::done() const noexcept {
  return impl_->started && !impl_->pending && static_cast<int>(impl_->raws.size()) >= impl_->opt.budget;
}
int SelfTest::probes_observed() const noexcept { return static_cast<int>(impl_->raws.size()); }
const Options& SelfTest::options() const noexcept { return impl_->opt; }
const std::vector<Contract>& SelfTest::pool() const noexcept { return impl_->pool; }
Eigen::VectorXd SelfTest::posterior() const { return impl_->belief.probs(); }

Evidence SelfTest::evidence() const {
  const auto& s = *impl_;
  const auto& belief = s.belief;
  const Eigen::VectorXd p = belief.probs();
  const int map = belief.map_index();
  Evidence e;
  e.expected = s.opt.expected;
  e.identified = s.pool[static_cast<std::size_t>(map)];
  e.map_posterior = p[map];

  // per-field confidence: posterior mass of the members that agree with the MAP on that field
  for (Field f : all_fields()) {
    double c = 0;
    for (int h = 0; h < belief.size(); ++h)
      if (same_field(s.pool[static_cast<std::size_t>(h)], e.identified, f)) c += p[h];
    e.confidence[static_cast<std::size_t>(f)] = std::min(c, 1.0);
  }

  // misspecification: replay the probes through a fresh replica of the MAP (chi-square per dof)
  if (!s.raws.empty()) {
    Decoder replay(e.identified);
    double sum = 0;
    for (std::size_t k = 0; k < s.raws.size(); ++k) {
      const Action pred = replay.step(s.raws[k], s.rotations[k]);
      for (int c = 0; c < kPoseDim; ++c) {
        const auto i = static_cast<std::size_t>(c);
        const double r = (s.responses[k][c] - s.opt.model.alpha[i] * pred[c]) / s.opt.model.sigma[i];
        sum += r * r;
      }
    }
    e.fit_ratio = sum / static_cast<double>(kPoseDim * s.raws.size());
  }

  // what this run cannot observe
  const auto frame = static_cast<std::size_t>(Field::kFrame);
  if (s.opt.frame_rotation == FrameRotation::kIdentity) {
    e.checkable[frame] = false;
    e.unchecked_reason[frame] =
        "tool frame under identity rotation: with R = I a tool-frame command decodes exactly like a base-frame one";
  } else if (!s.raws.empty() && s.min_angle < s.opt.min_frame_angle) {
    e.checkable[frame] = false;
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "tool frame under (near-)identity rotation: the TCP orientation came within %.3f rad of identity "
                  "(< %g rad), where tool-frame and base-frame commands coincide",
                  s.min_angle, s.opt.min_frame_angle);
    e.unchecked_reason[frame] = buf;
  }
  if (e.identified.target() == Target::kAbsolute) {
    const auto scale = static_cast<std::size_t>(Field::kScale);
    e.checkable[scale] = false;
    e.unchecked_reason[scale] =
        "scale under absolute targets: an absolute command sets a pose offset from the start pose, and the "
        "calibrated gain describes delta commands, so the wiring's scale is not verified";
  }
  return e;
}

Verdict SelfTest::verdict() const {
  const auto& s = *impl_;
  const Evidence e = evidence();
  const double ratio = e.identified.target() == Target::kAbsolute && s.opt.misspec_ratio_absolute
                           ? *s.opt.misspec_ratio_absolute
                           : s.opt.misspec_ratio;
  Verdict v = decide_verdict(e, s.opt.confidence_floor, ratio);
  v.probe_steps = static_cast<int>(s.raws.size());
  v.amplitude = s.opt.amplitude;
  v.displacement = s.path;
  v.max_excursion = s.excursion;
  v.rotation = s.turned;
  v.finger_travel = s.have_fingers && s.started && s.start.fingers ? s.fingers : -1.0;
  v.gripper_hold = s.gripper_hold;
  if (s.raws.empty() && v.status != Status::kInconclusive) {  // e.g. a one-member pool: never pass without evidence
    v.status = Status::kInconclusive;
    v.reason = "no probe responses observed. Abstaining.";
  }
  // never a verdict from numbers that overflowed (the inputs are bounded, so this is a last guard)
  if (!impl_->belief.probs().allFinite() || !std::isfinite(e.fit_ratio)) {
    v.status = Status::kInconclusive;
    v.reason = "the posterior or the fit is not finite (the observed responses are out of range). Abstaining.";
  }
  return v;
}

}  // namespace actionshift::selftest
