#pragma once
/// \file
/// Delay-aware expert: the scripted expert plus a Smith predictor over its own action history.
///
/// What it does, each step:
///  1. lag estimate: it keeps the TCP positions it observed and the actions it emitted; for every
///     candidate lag L in {0, ..., 4} it accumulates the squared error between the observed TCP
///     displacement of the last step and the displacement predicted from the action emitted L + 1
///     steps ago (kResponseGain * 0.1 m per unit). The estimate is the argmin (ties: the smaller
///     lag), or the known lag if one is given (the privileged DAgger teacher of mlp-delay-aware);
///  2. prediction: the last L emitted actions are still in the pipeline, so it shifts the observed
///     TCP position by their predicted displacement (and the object with it when the object is
///     held or being pushed), giving the state at which its next action will take effect;
///  3. it returns the stateless expert's action (expert.hpp) for that predicted observation.
/// It remembers only its own outputs and observations, never the contract.

#include "actionshift/policy/policy.hpp"

#include <array>
#include <memory>
#include <optional>

namespace actionshift::policy {

/// Displacement achieved per step per unit of canonical translation, as a fraction of 0.1 m
/// (measured on the Bullet Panda under the identity contract: about 0.3-0.45).
inline constexpr double kResponseGain = 0.4;
/// Largest lag the predictor considers.
inline constexpr int kMaxPredictedLag = 4;

/// The delay-aware expert (name "expert-delay-aware").
class DelayAwareExpert final : public Policy {
 public:
  /// `known_lag`: use this lag instead of estimating it (privileged teacher); nullopt to estimate.
  explicit DelayAwareExpert(sim::TaskId task, std::optional<int> known_lag = std::nullopt);

  void reset() override;
  Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) override;
  std::string name() const override { return "expert-delay-aware"; }
  std::string sha256() const override;
  sim::TaskId task() const override { return task_; }
  std::unique_ptr<Policy> clone() const override;

  /// Lag the predictor used at the last step.
  int lag_estimate() const { return lag_; }
  /// Record that `executed` (not the action this policy returned) was sent to the environment at
  /// the last step, e.g. when a DAgger run executed the learner's action instead.
  void override_last_action(const Action& executed);
  /// The observation as predicted for the moment the next action takes effect (for tests).
  Eigen::VectorXd predict_observation(const Eigen::Ref<const Eigen::VectorXd>& obs, int lag) const;

 private:
  sim::TaskId task_;
  std::optional<int> known_lag_;
  std::array<Action, kMaxPredictedLag + 1> history_{};  ///< emitted actions, most recent first
  int steps_{0};
  Eigen::Vector3d last_tcp_{Eigen::Vector3d::Zero()};
  std::array<double, kMaxPredictedLag + 1> evidence_{};
  int lag_{0};
};

/// Version string identifying the delay-aware expert's behaviour.
inline constexpr std::string_view kDelayAwareExpertVersion = "actionshift-expert-delay-aware-v1";

}  // namespace actionshift::policy
