#include "actionshift/adapt/methods.hpp"

#include "actionshift/core/transforms.hpp"

#include <array>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace actionshift::adapt {

std::vector<Action> probe_candidates(double amplitude) {
  std::vector<Action> c;
  for (double s : {1.0, -1.0})
    for (int ch = 0; ch < kPoseDim; ++ch) {
      Action a = Action::Zero();
      a[ch] = s * amplitude;
      c.push_back(a);
    }
  return c;
}

Action fixed_probe_pulse(int step, double amplitude) {
  Action a = Action::Zero();
  a[step % kPoseDim] = ((step / kPoseDim) % 2 == 0 ? 1.0 : -1.0) * amplitude;
  return a;
}

std::vector<int> active_hypotheses(const Eigen::VectorXd& p, int max_active, double mass) {
  std::vector<int> order(static_cast<std::size_t>(p.size()));
  std::vector<int> out(std::min(order.size(), static_cast<std::size_t>(std::max(1, max_active))));
  out.resize(static_cast<std::size_t>(active_set(p, max_active, mass, order, out)));
  return out;
}

namespace {

void check_options(const ProbeOptions& o) {
  if (o.budget < 0) throw std::invalid_argument("probe budget must be nonnegative");
  if (!(o.amplitude > 0) || !std::isfinite(o.amplitude)) throw std::invalid_argument("probe amplitude must be finite and positive");
  if (o.max_active < 1) throw std::invalid_argument("max_active must be at least 1");
}

const ProbeOptions& checked(const ProbeOptions& o) {
  check_options(o);
  return o;
}

}  // namespace

std::vector<double> expected_posterior_entropy(const PoolBelief& b, const std::vector<Action>& candidates, const Mat3& R,
                                               const ProbeOptions& o) {
  ProbeSelector sel(b.size(), o.max_active);
  sel.select_active(b, o.max_active, o.active_mass);
  std::vector<double> out;
  out.reserve(candidates.size());
  for (const auto& c : candidates) out.push_back(sel.expected_entropy(b, c, R, o.calibrated_preview, o.lag_aware_preview));
  return out;
}

std::vector<double> expected_response_magnitude(const PoolBelief& b, const std::vector<Action>& candidates, const Mat3& R,
                                                const ProbeOptions& o) {
  ProbeSelector sel(b.size(), o.max_active);
  sel.select_active(b, o.max_active, o.active_mass);
  std::vector<double> out;
  out.reserve(candidates.size());
  for (const auto& c : candidates) {
    double m = 0;
    sel.expected_entropy(b, c, R, o.calibrated_preview, o.lag_aware_preview, &m);
    out.push_back(m);
  }
  return out;
}

// ---- probing

ProbingAdapter::ProbingAdapter(std::vector<Contract> pool, ResponseModel model, ProbeStrategy strategy, ProbeOptions options)
    : belief_(std::move(pool), model),
      strategy_(strategy),
      options_(checked(options)),
      selector_(belief_.size(), options_.max_active),
      candidates_(probe_candidates(options.amplitude)) {}

std::string ProbingAdapter::name() const {
  switch (strategy_) {
    case ProbeStrategy::kFixed: return "fixed_probes";
    case ProbeStrategy::kRandom: return "random_probes";
    default: return "entropy_probes";
  }
}

void ProbingAdapter::begin_episode(std::uint64_t episode_seed) {
  belief_.reset();
  rng_ = Rng(derive_seed({episode_seed, 0x70726f6265ULL}));  // "probe"
  steps_ = 0;
  last_ = {};
}

Action ProbingAdapter::encode(const Action& canonical, const Mat3& R) {
  const Action task = belief_.map_encode(canonical, R);
  const bool probing = steps_ < options_.budget;
  const int step = steps_++;
  last_ = {probing, -1.0};
  if (!probing) return task;
  switch (strategy_) {
    case ProbeStrategy::kFixed:
      return fixed_probe_pulse(step, options_.amplitude);
    case ProbeStrategy::kRandom: {
      Action a = Action::Zero();
      for (int ch = 0; ch < kPoseDim; ++ch) a[ch] = (2.0 * rng_.uniform() - 1.0) * options_.amplitude;
      return a;
    }
    default: {
      selector_.select_active(belief_, options_.max_active, options_.active_mass);
      std::array<double, kNumCandidates> eh, motion;
      for (std::size_t i = 0; i < kNumCandidates; ++i)
        eh[i] = selector_.expected_entropy(belief_, candidates_[i], R, options_.calibrated_preview, options_.lag_aware_preview,
                                           options_.motion_tiebreak ? &motion[i] : nullptr);
      std::size_t best = 0;
      for (std::size_t i = 1; i < kNumCandidates; ++i)
        if (eh[i] < eh[best]) best = i;
      if (options_.motion_tiebreak) {
        const double cutoff = eh[best] + options_.entropy_tolerance;
        for (std::size_t i = 0; i < kNumCandidates; ++i)
          if (eh[i] <= cutoff && motion[i] < motion[best]) best = i;
      }
      return candidates_[best];
    }
  }
}

// ---- DualABI

DualAbiAdapter::DualAbiAdapter(std::vector<Contract> pool, ResponseModel model, double regret_threshold, ProbeOptions options,
                               int window)
    : belief_(std::move(pool), model),
      threshold_(regret_threshold),
      options_(checked(options)),
      window_(window),
      selector_(belief_.size(), options_.max_active, std::max(window, 0)),
      candidates_(probe_candidates(options.amplitude)) {
  if (window_ < 1) throw std::invalid_argument("DualABI recent window must be at least 1");
  if (!std::isfinite(threshold_) || threshold_ < 0) throw std::invalid_argument("DualABI regret threshold must be finite and nonnegative");
  recent_.assign(static_cast<std::size_t>(window_), Action::Zero());
}

void DualAbiAdapter::begin_episode(std::uint64_t) {
  belief_.reset();
  fresh_ = true;
  stopped_ = false;
  steps_ = 0;
  last_ = {};
}

void DualAbiAdapter::push_recent(const Action& a) {
  if (fresh_) {
    std::fill(recent_.begin(), recent_.end(), a);
    fresh_ = false;
    return;
  }
  std::rotate(recent_.rbegin(), recent_.rbegin() + 1, recent_.rend());  // shift towards the old end
  recent_.front() = a;
}

Eigen::MatrixXd DualAbiAdapter::pairwise_task_error(const std::vector<int>& active, const Mat3& R) const {
  ProbeSelector sel(belief_.size(), static_cast<int>(active.size()), window_);
  sel.set_active(belief_, active);
  sel.compute_task_error(belief_, recent_, R);
  return sel.task_error();
}

double DualAbiAdapter::regret(const Eigen::VectorXd& p, const Eigen::MatrixXd& E) {
  Eigen::Index best = 0;
  for (Eigen::Index i = 1; i < p.size(); ++i)
    if (p[i] > p[best]) best = i;
  return E.row(best).dot(p);
}

std::vector<double> DualAbiAdapter::expected_future_regret(const std::vector<int>& active, const Eigen::MatrixXd& E,
                                                           const Mat3& R) const {
  ProbeSelector sel(belief_.size(), static_cast<int>(active.size()), window_);
  sel.set_active(belief_, active);
  sel.set_task_error(E);
  std::vector<double> out;
  for (const auto& c : candidates_)
    out.push_back(sel.expected_future_regret(belief_, c, R, options_.calibrated_preview, options_.lag_aware_preview));
  return out;
}

Action DualAbiAdapter::encode(const Action& canonical, const Mat3& R) {
  push_recent(canonical);
  const Action task = belief_.map_encode(canonical, R);
  const bool eligible = steps_ < options_.budget && !stopped_;
  ++steps_;
  last_ = {false, -1.0};
  if (!eligible) return task;
  selector_.select_active(belief_, options_.max_active, options_.active_mass);
  selector_.compute_task_error(belief_, recent_, R);
  const double current = selector_.current_regret();
  last_.task_regret = current;
  if (current < threshold_) {  // sticky: no more probing this episode
    stopped_ = true;
    return task;
  }
  std::array<double, kNumCandidates> ef;
  for (std::size_t c = 0; c < kNumCandidates; ++c)
    ef[c] = selector_.expected_future_regret(belief_, candidates_[c], R, options_.calibrated_preview, options_.lag_aware_preview);
  std::size_t best = 0;
  double best_score = -1;
  for (std::size_t c = 0; c < ef.size(); ++c) {
    const double score = std::max(current - ef[c], 0.0);
    if (score > best_score) {
      best_score = score;
      best = c;
    }
  }
  last_.probe = true;
  return candidates_[best];
}

}  // namespace actionshift::adapt
