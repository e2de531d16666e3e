#pragma once
/// \file The stateful decoder: tracked target + lag FIFO per environment, batched over N
/// environments (docs/reference.md, *Contracts*). Sized once at construction; step() never allocates.

#include "actionshift/core/contract.hpp"
#include "actionshift/core/transforms.hpp"
#include "actionshift/core/types.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace actionshift {

/// Largest num_envs x (lag + 1) a Decoder accepts: each slot holds 7 doubles, so this is about 0.9 GB.
inline constexpr std::int64_t kMaxDecoderSlots = std::int64_t{1} << 24;

/// Per-environment decoder state for one contract (the Data to the Contract's Model).
///
/// Each step, for each environment: if its reset flag is set, its tracked target and lag history
/// are zeroed first (the first step of a new episode); then decode() against the tracked target;
/// then the whole 7-vector goes through the lag FIFO (zeros for the first `lag` steps of an
/// episode). The Decoder owns a copy of its contract, so a mismatched pair cannot exist.
class Decoder {
 public:
  using Batch = Eigen::Matrix<double, kActionDim, Eigen::Dynamic>;  ///< 7 × N, one column per env

  /// Throws std::invalid_argument if num_envs < 1 or num_envs x (lag + 1) > kMaxDecoderSlots.
  explicit Decoder(const Contract& c, int num_envs = 1)
      : contract_(c), num_envs_(num_envs) {
    if (num_envs < 1) throw std::invalid_argument("decoder needs at least one environment (got " + std::to_string(num_envs) + ")");
    if (static_cast<std::int64_t>(num_envs) * (c.lag() + 1) > kMaxDecoderSlots)
      throw std::invalid_argument("decoder: num_envs x (lag + 1) must be at most " + std::to_string(kMaxDecoderSlots) +
                                  " (got " + std::to_string(num_envs) + " x " + std::to_string(c.lag() + 1) +
                                  "): its targets and lag FIFOs would take about 1 GB or more");
    targets_ = Eigen::Matrix<double, kPoseDim, Eigen::Dynamic>::Zero(kPoseDim, num_envs);
    history_ = Batch::Zero(kActionDim, static_cast<Eigen::Index>(c.lag()) * num_envs);
  }

  const Contract& contract() const noexcept { return contract_; }
  int num_envs() const noexcept { return num_envs_; }

  /// Clears one environment's tracked target and lag history.
  void reset(int env) {
    check_env(env);
    targets_.col(env).setZero();
    for (int s = 0; s < contract_.lag(); ++s) history_.col(s * num_envs_ + env).setZero();
  }
  /// Clears every environment.
  void reset_all() {
    targets_.setZero();
    history_.setZero();
    head_ = 0;
  }

  /// The tracked target of `env` (zero at episode start; what absolute commands are offsets from).
  Pose6 tracked_target(int env = 0) const {
    check_env(env);
    return targets_.col(env);
  }

  /// Batched step. `raw` and `out` are 7 × N (they may not alias). `R` is empty (identity for
  /// every env), size 1 (broadcast) or size N. `reset_mask` is empty or size N.
  /// Throws std::invalid_argument on a shape mismatch.
  void step(const Eigen::Ref<const Batch>& raw, std::span<const Mat3> R, std::span<const bool> reset_mask,
            Eigen::Ref<Batch> out) {
    if (raw.cols() != num_envs_ || out.cols() != num_envs_)
      throw std::invalid_argument("decoder batch size is " + std::to_string(num_envs_) + ", got " +
                                  std::to_string(raw.cols()) + " actions");
    if (!(R.empty() || R.size() == 1 || R.size() == static_cast<std::size_t>(num_envs_)))
      throw std::invalid_argument("decoder needs 0, 1 or N rotation matrices");
    if (!(reset_mask.empty() || reset_mask.size() == static_cast<std::size_t>(num_envs_)))
      throw std::invalid_argument("decoder reset mask must be empty or have one flag per environment");
    static const Mat3 kIdentity = Mat3::Identity();
    const int lag = contract_.lag();
    for (int e = 0; e < num_envs_; ++e) {
      if (!reset_mask.empty() && reset_mask[static_cast<std::size_t>(e)]) reset(e);
      const Mat3& Re = R.empty() ? kIdentity : R[R.size() == 1 ? 0 : static_cast<std::size_t>(e)];
      Pose6 next;
      const Action canonical = decode(contract_, raw.col(e), Re, targets_.col(e), &next);
      targets_.col(e) = next;
      if (lag == 0) {
        out.col(e) = canonical;
      } else {
        auto slot = history_.col(head_ * num_envs_ + e);
        out.col(e) = slot;
        slot = canonical;
      }
    }
    if (lag > 0) head_ = (head_ + 1) % lag;
  }

  /// What step(raw, R) would return for `env`, without changing any state: the lag FIFO's oldest
  /// entry when lag > 0 (the raw action only takes effect `lag` steps later), else the decode
  /// against the current tracked target. Used by adapters to preview a probe (lag-aware).
  Action preview(const Action& raw, const Mat3& R = Mat3::Identity(), int env = 0) const {
    check_env(env);
    if (contract_.lag() > 0) return history_.col(head_ * num_envs_ + env);
    return decode(contract_, raw, R, targets_.col(env));
  }

  /// Single-environment step (num_envs must be 1). `reset` = this is the first step of an episode.
  Action step(const Action& raw, const Mat3& R = Mat3::Identity(), bool reset_first = false) {
    if (num_envs_ != 1) throw std::invalid_argument("single-action step needs a decoder with one environment");
    if (reset_first) reset(0);
    Pose6 next;
    const Action canonical = decode(contract_, raw, R, targets_.col(0), &next);
    targets_.col(0) = next;
    const int lag = contract_.lag();
    if (lag == 0) return canonical;
    auto slot = history_.col(head_);
    const Action delayed = slot;
    slot = canonical;
    head_ = (head_ + 1) % lag;
    return delayed;
  }

 private:
  void check_env(int env) const {
    if (env < 0 || env >= num_envs_)
      throw std::invalid_argument("environment index " + std::to_string(env) + " out of range [0, " +
                                  std::to_string(num_envs_) + ")");
  }

  Contract contract_;
  int num_envs_;
  Eigen::Matrix<double, kPoseDim, Eigen::Dynamic> targets_;  // 6 × N tracked targets
  Batch history_;                                            // 7 × (lag·N) ring, slot-major
  int head_{0};                                              // oldest slot (shared: envs step together)
};

}  // namespace actionshift
