#include "actionshift/adapt/batched_belief.hpp"

#include "actionshift/core/transforms.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace actionshift::adapt {

BatchedPoolBelief::BatchedPoolBelief(std::vector<Contract> pool, ResponseModel model, int num_envs)
    : pool_(std::move(pool)), model_(model), num_envs_(num_envs) {
  if (pool_.empty()) throw std::invalid_argument("pool belief needs at least one hypothesis");
  if (num_envs < 1) throw std::invalid_argument("batched belief needs at least one environment (got " + std::to_string(num_envs) + ")");
  model_.validate();
  replicas_.reserve(pool_.size());
  for (const auto& c : pool_) replicas_.emplace_back(c, num_envs);
  logp_.resize(num_envs, size());
  ll_.resize(num_envs, size());
  pred_.resize(kActionDim, num_envs);
  max_.resize(num_envs);
  sum_.resize(num_envs);
  reset();
}

void BatchedPoolBelief::reset() {
  logp_.setConstant(-std::log(static_cast<double>(size())));
  for (auto& r : replicas_) r.reset_all();
}

void BatchedPoolBelief::update(const Eigen::Ref<const Batch>& raw, const Eigen::Ref<const PoseBatch>& observed,
                               std::span<const Mat3> R, std::span<const bool> reset_mask, std::span<const bool> invalid_mask) {
  if (raw.cols() != num_envs_ || observed.cols() != num_envs_)
    throw std::invalid_argument("batched belief has " + std::to_string(num_envs_) + " environments, got " +
                                std::to_string(raw.cols()) + " actions and " + std::to_string(observed.cols()) + " responses");
  if (!(invalid_mask.empty() || invalid_mask.size() == static_cast<std::size_t>(num_envs_)))
    throw std::invalid_argument("invalid mask must be empty or have one flag per environment");
  Eigen::Array<double, kPoseDim, 1> alpha, inv_sigma;
  for (int c = 0; c < kPoseDim; ++c) {
    alpha[c] = model_.alpha[static_cast<std::size_t>(c)];
    inv_sigma[c] = 1.0 / model_.sigma[static_cast<std::size_t>(c)];
  }
  // 1–2: every hypothesis decodes every environment's raw action; its log-likelihood column
  for (int h = 0; h < size(); ++h) {
    replicas_[static_cast<std::size_t>(h)].step(raw, R, reset_mask, pred_);
    ll_.col(h) = -0.5 * (((observed.array() - pred_.topRows<kPoseDim>().array().colwise() * alpha).colwise() * inv_sigma)
                             .square()
                             .colwise()
                             .sum())
                            .transpose();
  }
  // 4: logp ← logp + ll − logsumexp_h(logp + ll), per environment (row)
  ll_ += logp_;
  max_ = ll_.rowwise().maxCoeff();
  logp_ = (ll_.colwise() - max_).array().exp();  // scratch: exp(x − max)
  sum_ = logp_.rowwise().sum();
  for (int e = 0; e < num_envs_; ++e)
    max_[e] = std::isfinite(max_[e]) ? max_[e] + std::log(sum_[e]) : max_[e];  // log Σ exp, as logsumexp()
  logp_ = ll_.colwise() - max_;
  // 3: a transition across an episode boundary carries no evidence
  if (!invalid_mask.empty())
    for (int e = 0; e < num_envs_; ++e)
      if (invalid_mask[static_cast<std::size_t>(e)]) logp_.row(e).setConstant(-std::log(static_cast<double>(size())));
}

void BatchedPoolBelief::check_env(int env) const {
  if (env < 0 || env >= num_envs_)
    throw std::invalid_argument("environment index " + std::to_string(env) + " out of range [0, " + std::to_string(num_envs_) + ")");
}

int BatchedPoolBelief::map_index(int env) const {
  check_env(env);
  int best = 0;
  for (int h = 1; h < size(); ++h)
    if (logp_(env, h) > logp_(env, best)) best = h;
  return best;
}

void BatchedPoolBelief::map_indices(std::span<int> out) const {
  if (out.size() != static_cast<std::size_t>(num_envs_)) throw std::invalid_argument("map_indices needs one slot per environment");
  for (int e = 0; e < num_envs_; ++e) out[static_cast<std::size_t>(e)] = 0;
  for (int h = 1; h < size(); ++h)
    for (int e = 0; e < num_envs_; ++e) {
      auto& best = out[static_cast<std::size_t>(e)];
      if (logp_(e, h) > logp_(e, best)) best = h;
    }
}

Action BatchedPoolBelief::map_encode(int env, const Action& canonical, const Mat3& R) const {
  const int h = map_index(env);
  const Decoder& rep = replicas_[static_cast<std::size_t>(h)];
  return actionshift::encode(rep.contract(), canonical, R, rep.tracked_target(env));
}

double BatchedPoolBelief::entropy(int env) const {
  check_env(env);
  double ent = 0;
  for (int h = 0; h < size(); ++h)
    if (std::isfinite(logp_(env, h))) ent -= std::exp(logp_(env, h)) * logp_(env, h);
  return ent;
}

}  // namespace actionshift::adapt
