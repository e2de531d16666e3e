#pragma once
/// \file The pool belief of many environments at once, stored as structure of arrays, for users
/// who step many environments per thread (the reference's batched `update`, one call per step).
///
/// Layout: one batched Decoder per hypothesis (its tracked targets and lag FIFOs for every
/// environment, core/decoder.hpp) and the log-belief as an N × H matrix whose column h holds
/// hypothesis h for all N environments, so the likelihood of a hypothesis is one vectorised pass
/// over the environments and the per-environment normalisation is a row-wise log-sum-exp. Every
/// buffer is sized at construction; update() allocates nothing.
///
/// Each environment's belief equals what a PoolBelief (pool_belief.hpp) fed the same transitions
/// holds, to rounding (the test checks 1e-12).

#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/decoder.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace actionshift::adapt {

class BatchedPoolBelief {
 public:
  using Batch = Decoder::Batch;                                    ///< 7 × N actions, one column per env
  using PoseBatch = Eigen::Matrix<double, kPoseDim, Eigen::Dynamic>;  ///< 6 × N responses

  /// Throws std::invalid_argument for an empty pool, num_envs < 1 or an invalid response model.
  BatchedPoolBelief(std::vector<Contract> pool, ResponseModel model, int num_envs);

  int size() const noexcept { return static_cast<int>(pool_.size()); }
  int num_envs() const noexcept { return num_envs_; }
  const std::vector<Contract>& pool() const noexcept { return pool_; }
  const ResponseModel& model() const noexcept { return model_; }

  /// Every environment: uniform belief and fresh replicas.
  void reset();

  /// One transition of every environment. `raw` 7 × N, `observed` 6 × N; `R` empty (identity),
  /// size 1 (broadcast) or N; `reset_mask` / `invalid_mask` empty or N flags with the meaning of
  /// PoolBelief::update (restart that environment's replicas first / discard its evidence and
  /// return it to uniform). Throws std::invalid_argument on a shape mismatch.
  void update(const Eigen::Ref<const Batch>& raw, const Eigen::Ref<const PoseBatch>& observed, std::span<const Mat3> R = {},
              std::span<const bool> reset_mask = {}, std::span<const bool> invalid_mask = {});

  /// N × H log-probabilities (row e: environment e).
  const Eigen::MatrixXd& log_probs() const noexcept { return logp_; }
  /// MAP hypothesis of environment `env` (first index wins ties).
  int map_index(int env) const;
  /// The MAP index of every environment.
  void map_indices(std::span<int> out) const;
  /// Encode `canonical` for environment `env` with its MAP hypothesis and that replica's tracked target.
  Action map_encode(int env, const Action& canonical, const Mat3& R) const;
  /// Shannon entropy of environment `env`'s belief [nats].
  double entropy(int env) const;

 private:
  void check_env(int env) const;

  std::vector<Contract> pool_;
  ResponseModel model_;
  int num_envs_;
  std::vector<Decoder> replicas_;  // one per hypothesis, each batched over the environments
  Eigen::MatrixXd logp_;           // N × H
  Eigen::MatrixXd ll_;             // N × H scratch
  Batch pred_;                     // 7 × N scratch
  Eigen::VectorXd max_, sum_;      // N scratch
};

}  // namespace actionshift::adapt
