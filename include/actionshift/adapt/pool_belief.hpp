#pragma once
/// \file Exact Bayesian belief over a declared pool of contracts (docs/reference.md, *Pool belief*): one decoder
/// replica per hypothesis (its own tracked target and lag FIFO), Gaussian likelihood of the
/// observed TCP response from the calibrated response model, MAP encoding.

#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/decoder.hpp"

#include <Eigen/Core>

#include <vector>

namespace actionshift::adapt {

class PoolBelief {
 public:
  /// Throws std::invalid_argument for an empty pool or an invalid response model.
  PoolBelief(std::vector<Contract> pool, ResponseModel model);

  int size() const noexcept { return static_cast<int>(pool_.size()); }
  const std::vector<Contract>& pool() const noexcept { return pool_; }
  const ResponseModel& model() const noexcept { return model_; }

  /// Start of an episode: uniform belief (−ln H each) and fresh replicas.
  void reset();

  /// One transition (reference `update`, masks for this one environment):
  /// 1. every replica decodes `raw` with rotation `R` (`reset_mask`: restart the replicas first,
  ///    i.e. this is the first step of an episode);
  /// 2. log-likelihood of `observed` under each replica's prediction;
  /// 3. `invalid_mask`: the transition spans an episode boundary, so its evidence is discarded
  ///    and the belief returns to uniform;
  /// 4. logp ← logp + ll − logsumexp(logp + ll).
  void update(const Action& raw, const Pose6& observed, const Mat3& R, bool reset_mask = false,
              bool invalid_mask = false);

  /// argmax of the belief (the first index wins ties, so pool[0] before any evidence).
  int map_index() const;
  /// Encode `canonical` with the MAP hypothesis and its replica's tracked target.
  Action map_encode(const Action& canonical, const Mat3& R) const;
  /// Encode with hypothesis h (its replica's tracked target).
  Action encode_with(int h, const Action& canonical, const Mat3& R) const;

  const Eigen::VectorXd& log_probs() const noexcept { return logp_; }
  Eigen::VectorXd probs() const;
  /// Shannon entropy of the belief [nats].
  double entropy() const;
  const Decoder& replica(int h) const { return replicas_[static_cast<std::size_t>(h)]; }

  /// Predicted canonical action of every hypothesis for a candidate raw action, without changing
  /// state. Lag-aware: a lagged hypothesis predicts what its FIFO releases this step (the candidate
  /// only acts `lag` steps later). Lag-blind (the reference's preview): decode ignoring the FIFO.
  void preview(const Action& raw, const Mat3& R, bool lag_aware, std::vector<Action>& out) const;

 private:
  std::vector<Contract> pool_;
  ResponseModel model_;
  std::vector<Decoder> replicas_;
  Eigen::VectorXd logp_;
  Eigen::VectorXd scratch_;
};

/// log Σ exp(v), stable.
double logsumexp(const Eigen::Ref<const Eigen::VectorXd>& v);

}  // namespace actionshift::adapt
