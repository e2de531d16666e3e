#include "actionshift/adapt/pool_belief.hpp"

#include "actionshift/core/transforms.hpp"

#include <cmath>
#include <stdexcept>

namespace actionshift::adapt {

double logsumexp(const Eigen::Ref<const Eigen::VectorXd>& v) {
  const double m = v.maxCoeff();
  if (!std::isfinite(m)) return m;
  return m + std::log((v.array() - m).exp().sum());
}

PoolBelief::PoolBelief(std::vector<Contract> pool, ResponseModel model) : pool_(std::move(pool)), model_(model) {
  if (pool_.empty()) throw std::invalid_argument("pool belief needs at least one hypothesis");
  model_.validate();
  replicas_.reserve(pool_.size());
  for (const auto& c : pool_) replicas_.emplace_back(c);
  logp_.resize(size());
  scratch_.resize(size());
  reset();
}

void PoolBelief::reset() {
  logp_.setConstant(-std::log(static_cast<double>(size())));
  for (auto& r : replicas_) r.reset_all();
}

void PoolBelief::update(const Action& raw, const Pose6& observed, const Mat3& R, bool reset_mask, bool invalid_mask) {
  for (int h = 0; h < size(); ++h) {
    const Action pred = replicas_[static_cast<std::size_t>(h)].step(raw, R, reset_mask);
    scratch_[h] = model_.log_likelihood(pred, observed);
  }
  if (invalid_mask) {
    logp_.setConstant(-std::log(static_cast<double>(size())));
    return;
  }
  scratch_ += logp_;
  logp_ = scratch_.array() - logsumexp(scratch_);
}

int PoolBelief::map_index() const {
  int best = 0;
  for (int h = 1; h < size(); ++h)
    if (logp_[h] > logp_[best]) best = h;
  return best;
}

Action PoolBelief::encode_with(int h, const Action& canonical, const Mat3& R) const {
  const auto& rep = replicas_[static_cast<std::size_t>(h)];
  return actionshift::encode(rep.contract(), canonical, R, rep.tracked_target());
}

Action PoolBelief::map_encode(const Action& canonical, const Mat3& R) const {
  return encode_with(map_index(), canonical, R);
}

Eigen::VectorXd PoolBelief::probs() const { return logp_.array().exp(); }

double PoolBelief::entropy() const {
  double h = 0;
  for (int i = 0; i < size(); ++i)
    if (std::isfinite(logp_[i])) h -= std::exp(logp_[i]) * logp_[i];
  return h;
}

void PoolBelief::preview(const Action& raw, const Mat3& R, bool lag_aware, std::vector<Action>& out) const {
  out.resize(pool_.size());
  for (std::size_t h = 0; h < pool_.size(); ++h) {
    const auto& rep = replicas_[h];
    out[h] = lag_aware ? rep.preview(raw, R) : actionshift::decode(rep.contract(), raw, R, rep.tracked_target());
  }
}

}  // namespace actionshift::adapt
