#pragma once
/// \file The synthetic stand-in robot of the self-test demos (docs/reference.md, *Self-test*): the hidden
/// contract's stateful decoder with R = I, then a TCP that moves by response = α ⊙ canonical[0:6] +
/// σ·N(0, 1) per step (translation added to the position, rotation vector composed onto the
/// orientation). Deterministic in its seed; no simulator.

#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/selftest/selftest.hpp"

#include <cstdint>

namespace actionshift::selftest {

class SyntheticRobot {
 public:
  /// `hidden` is the robot's true wiring; `model` its response (α ≠ 0, σ ≥ 0 is not re-checked).
  SyntheticRobot(const Contract& hidden, const adapt::ResponseModel& model, std::uint64_t seed);

  /// Current TCP pose (starts at the origin with identity orientation).
  const TcpPose& pose() const noexcept { return pose_; }
  /// Executes one raw action: decode through the hidden contract, move by the noisy response.
  void send(const Action& raw);
  /// The canonical action the hidden decoder produced on the last send().
  const Action& last_canonical() const noexcept { return canonical_; }

 private:
  Decoder decoder_;
  adapt::ResponseModel model_;
  Rng rng_;
  TcpPose pose_;
  Action canonical_{Action::Zero()};
};

/// Drives `test` against `robot` until the budget is spent (begin, then next_probe/send/observe).
void run(SelfTest& test, SyntheticRobot& robot);

}  // namespace actionshift::selftest
