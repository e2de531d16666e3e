#pragma once
/// \file The adapter interface (docs/adapters.md): an adapter sits between the frozen backbone and the
/// hidden-contract environment. Each step it turns the backbone's canonical intent into the raw
/// action to send, then observes the raw action and the TCP response it caused.
///
/// Adapters are per environment and per worker thread; begin_episode() starts an episode. In the
/// reference's batched form this is the pair of masks of §4.3: the pending reset (replica decoders
/// restart with the wrapper's decoder) and the boundary transition (its evidence is discarded).

#include "actionshift/core/types.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace actionshift::adapt {

/// What the adapter did on its last encode().
struct StepInfo {
  bool probe{false};  ///< the raw action was a probe, not the backbone's intent
  double task_regret{-1.0};  ///< DualABI: regret of acting on the MAP now (−1 if not computed)
};

class Adapter {
 public:
  virtual ~Adapter() = default;
  /// Method name as used in job specs ("oracle", "no_adapt", "exact_belief", ...).
  virtual std::string name() const = 0;
  /// Start an episode: clear per-episode state. `episode_seed` seeds any randomness (random probes).
  virtual void begin_episode(std::uint64_t episode_seed) = 0;
  /// The raw action to send for the backbone's canonical intent. `R` is the TCP orientation
  /// before this step (identity under the `identity` rotation mode).
  virtual Action encode(const Action& canonical, const Mat3& R) = 0;
  /// After the step: the raw action that was sent (encode's result), the TCP response it
  /// caused (translation, rotation vector) and the same `R` as given to encode().
  virtual void observe(const Action& raw, const Pose6& response, const Mat3& R) = 0;
  /// The seventh evidence channel: the change of the mean finger position [m] over the coming
  /// observe()'s step. The runner calls it just before observe(), and only when the task's
  /// calibration has a finger channel; adapters that do not use it ignore it.
  virtual void observe_fingers(double /*finger_delta*/) {}
  /// What the last encode() did.
  virtual StepInfo last_step() const { return {}; }
};

}  // namespace actionshift::adapt
