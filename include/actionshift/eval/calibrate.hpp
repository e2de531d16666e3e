#pragma once
/// \file Response calibration on the unwrapped simulator (docs/reference.md, *Calibration and the response model*): random canonical
/// actions, the TCP response of each step, and a per-channel linear fit.

#include "actionshift/adapt/calibration.hpp"
#include "actionshift/sim/env.hpp"

#include <cstdint>
#include <memory>

namespace actionshift::eval {

struct CalibrationOptions {
  int episodes{16};                 ///< episodes of random actions
  int steps{50};                    ///< control steps per episode (at most the task horizon)
  std::uint64_t seed{20260720};     ///< the reference's calibration seed
};

/// Where the TCP pose is in a task's observation ("tcp_pose": position xyz then quaternion wxyz).
/// Throws std::invalid_argument if the layout has no 7-wide tcp_pose field.
adapt::TcpSlice tcp_slice(const sim::ObservationLayout& layout);

/// Runs the calibration: episode e resets with derive_seed({seed, e}) and draws uniform actions in
/// [−1, 1]^7 from Rng(derive_seed({seed, e, 1})); each step's TCP response is paired with its
/// action; an episode ended by a safety check contributes the steps before it.
/// Deterministic in (model, options).
adapt::ResponseCalibration calibrate(std::shared_ptr<const sim::EnvModel> model, const CalibrationOptions& options = {});

}  // namespace actionshift::eval
