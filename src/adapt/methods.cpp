#include "actionshift/adapt/methods.hpp"

#include "actionshift/core/transforms.hpp"

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
  const int n = static_cast<int>(p.size());
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return p[a] > p[b]; });
  std::vector<int> out;
  double covered = 0;
  for (int i : order) {
    if (static_cast<int>(out.size()) >= std::max(1, max_active)) break;
    if (!out.empty() && covered >= mass) break;
    out.push_back(i);
    covered += p[i];
  }
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

void check_options(const ProbeOptions& o) {
  if (o.budget < 0) throw std::invalid_argument("probe budget must be nonnegative");
  if (!(o.amplitude > 0) || !std::isfinite(o.amplitude)) throw std::invalid_argument("probe amplitude must be finite and positive");
  if (o.max_active < 1) throw std::invalid_argument("max_active must be at least 1");
}

// the observation a hypothesis predicts for its own prediction (see the header's two differences)
Pose6 simulated_observation(const ResponseModel& m, const Action& pred, bool calibrated) {
  return calibrated ? m.expected(pred) : Pose6(pred.head<kPoseDim>());
}

// posterior over `active` after observing `obs`, given the current log belief; returns its
// entropy [nats] (one exp per hypothesis and a single log)
double posterior(const PoolBelief& b, const std::vector<int>& active, const std::vector<Action>& preds, const Pose6& obs,
                 Eigen::VectorXd& out) {
  const auto& logp = b.log_probs();
  const auto n = static_cast<Eigen::Index>(active.size());
  out.resize(n);
  double m = -std::numeric_limits<double>::infinity();
  for (Eigen::Index j = 0; j < n; ++j) {
    const int h = active[static_cast<std::size_t>(j)];
    out[j] = logp[h] + b.model().log_likelihood(preds[static_cast<std::size_t>(h)], obs);
    m = std::max(m, out[j]);
  }
  double sum = 0, weighted = 0;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double x = out[j] - m;
    const double e = std::exp(x);
    out[j] = e;
    sum += e;
    weighted += e * x;
  }
  out /= sum;
  return std::log(sum) - weighted / sum;  // −Σ p ln p with ln p = x − ln Σe
}

// the belief restricted to its active hypotheses (ProbeOptions::max_active / active_mass)
struct ActiveBelief {
  Eigen::VectorXd p;        // probabilities of every hypothesis
  std::vector<int> active;  // indices, increasing
  double mass{0};           // Σ p over `active`
};

ActiveBelief active_belief(const PoolBelief& b, const ProbeOptions& o) {
  ActiveBelief a;
  a.p = b.probs();
  a.active = active_hypotheses(a.p, o.max_active, o.active_mass);
  for (int h : a.active) a.mass += a.p[h];
  return a;
}

}  // namespace

std::vector<double> expected_posterior_entropy(const PoolBelief& b, const std::vector<Action>& candidates, const Mat3& R,
                                               const ProbeOptions& o) {
  const auto [p, active, mass] = active_belief(b, o);
  std::vector<Action> preds;
  Eigen::VectorXd post;
  std::vector<double> out;
  out.reserve(candidates.size());
  for (const auto& c : candidates) {
    b.preview(c, R, o.lag_aware_preview, preds);
    double eh = 0;
    for (int h : active) {
      const double ent = posterior(b, active, preds,
                                   simulated_observation(b.model(), preds[static_cast<std::size_t>(h)], o.calibrated_preview), post);
      eh += p[h] / mass * ent;
    }
    out.push_back(eh);
  }
  return out;
}

std::vector<double> expected_response_magnitude(const PoolBelief& b, const std::vector<Action>& candidates, const Mat3& R,
                                                const ProbeOptions& o) {
  const auto [p, active, mass] = active_belief(b, o);
  std::vector<Action> preds;
  std::vector<double> out;
  out.reserve(candidates.size());
  for (const auto& c : candidates) {
    b.preview(c, R, o.lag_aware_preview, preds);
    double m = 0;
    for (int h : active) m += p[h] / mass * b.model().expected(preds[static_cast<std::size_t>(h)]).norm();
    out.push_back(m);
  }
  return out;
}

// ---- probing

ProbingAdapter::ProbingAdapter(std::vector<Contract> pool, ResponseModel model, ProbeStrategy strategy, ProbeOptions options)
    : belief_(std::move(pool), model), strategy_(strategy), options_(options), candidates_(probe_candidates(options.amplitude)) {
  check_options(options_);
}

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
      const auto eh = expected_posterior_entropy(belief_, candidates_, R, options_);
      std::size_t best = 0;
      for (std::size_t i = 1; i < eh.size(); ++i)
        if (eh[i] < eh[best]) best = i;
      if (options_.motion_tiebreak) {
        const auto motion = expected_response_magnitude(belief_, candidates_, R, options_);
        const double cutoff = eh[best] + options_.entropy_tolerance;
        for (std::size_t i = 0; i < eh.size(); ++i)
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
      options_(options),
      window_(window),
      candidates_(probe_candidates(options.amplitude)) {
  check_options(options_);
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
  const auto n = static_cast<Eigen::Index>(active.size());
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(n, n);
  const double inv_w = 1.0 / static_cast<double>(recent_.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& ri = belief_.replica(active[static_cast<std::size_t>(i)]);
    for (const Action& a : recent_) {
      const Action raw = actionshift::encode(ri.contract(), a, R, ri.tracked_target());
      for (Eigen::Index j = 0; j < n; ++j) {
        if (j == i) continue;
        const auto& rj = belief_.replica(active[static_cast<std::size_t>(j)]);
        const Action exec = actionshift::decode(rj.contract(), raw, R, rj.tracked_target());
        E(i, j) += (exec.head<kPoseDim>() - a.head<kPoseDim>()).norm() * inv_w;
      }
    }
  }
  return E;
}

double DualAbiAdapter::regret(const Eigen::VectorXd& p, const Eigen::MatrixXd& E) {
  Eigen::Index best = 0;
  for (Eigen::Index i = 1; i < p.size(); ++i)
    if (p[i] > p[best]) best = i;
  return E.row(best).dot(p);
}

std::vector<double> DualAbiAdapter::expected_future_regret(const std::vector<int>& active, const Eigen::MatrixXd& E,
                                                           const Mat3& R) const {
  const Eigen::VectorXd p_all = belief_.probs();
  Eigen::VectorXd p(static_cast<Eigen::Index>(active.size()));
  for (std::size_t j = 0; j < active.size(); ++j) p[static_cast<Eigen::Index>(j)] = p_all[active[j]];
  const double mass = p.sum();
  std::vector<Action> preds;
  Eigen::VectorXd post;
  std::vector<double> out;
  for (const auto& c : candidates_) {
    belief_.preview(c, R, options_.lag_aware_preview, preds);
    double ef = 0;
    for (std::size_t h = 0; h < active.size(); ++h) {
      posterior(belief_, active, preds,
                simulated_observation(belief_.model(), preds[static_cast<std::size_t>(active[h])], options_.calibrated_preview), post);
      ef += p[static_cast<Eigen::Index>(h)] / mass * regret(post, E);
    }
    out.push_back(ef);
  }
  return out;
}

Action DualAbiAdapter::encode(const Action& canonical, const Mat3& R) {
  push_recent(canonical);
  const Action task = belief_.map_encode(canonical, R);
  const bool eligible = steps_ < options_.budget && !stopped_;
  ++steps_;
  last_ = {false, -1.0};
  if (!eligible) return task;
  const Eigen::VectorXd p_all = belief_.probs();
  const std::vector<int> active = active_hypotheses(p_all, options_.max_active, options_.active_mass);
  const Eigen::MatrixXd E = pairwise_task_error(active, R);
  Eigen::VectorXd p(static_cast<Eigen::Index>(active.size()));
  for (std::size_t j = 0; j < active.size(); ++j) p[static_cast<Eigen::Index>(j)] = p_all[active[j]];
  p /= p.sum();
  const double current = regret(p, E);
  last_.task_regret = current;
  if (current < threshold_) {  // sticky: no more probing this episode
    stopped_ = true;
    return task;
  }
  const auto ef = expected_future_regret(active, E, R);
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
