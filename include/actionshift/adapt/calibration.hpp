#pragma once
/// \file Response calibration: per-channel gain α, noise σ and R² of the TCP response to random
/// canonical actions on the unwrapped environment (docs/reference.md, *Calibration and the response model*). The calibration JSON's hash
/// enters every job hash that uses it.

#include "actionshift/adapt/response.hpp"
#include "actionshift/core/types.hpp"

#include <nlohmann/json_fwd.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::adapt {

/// Result of fitting y ≈ α·x per channel (no intercept).
struct LinearFit {
  std::array<double, kPoseDim> alpha{};   ///< Σxy / Σx² (0 if Σx² = 0)
  std::array<double, kPoseDim> sigma{};   ///< population std of the residual, floored at 1e-4
  std::array<double, kPoseDim> fit_r2{};  ///< 1 − Σr² / Σ(y − ȳ)² (0 if the denominator is 0)
};

/// Fits each pose channel of `observed` against the same channel of `commanded`
/// (reference `fit_linear_response`). Throws std::invalid_argument if sizes differ or are empty.
LinearFit fit_linear_response(const std::vector<Pose6>& commanded, const std::vector<Pose6>& observed);

/// The finger channel's fit (the public reference implementation's finger channel, docs/reference.md): command = the gripper action, observed = the change
/// of the mean finger position (m) over the step.
struct GripperFit {
  int start{-1};        ///< offset of the two finger joint positions in the observation
  double alpha{0.0};    ///< Σxy / Σx²
  double sigma{0.0};    ///< population std of the residual, floored at 1e-4
  double fit_r2{0.0};
};

/// Fits the finger channel (same rules as fit_linear_response). Throws std::invalid_argument if the
/// sizes differ or are empty.
GripperFit fit_gripper_response(const std::vector<double>& commanded, const std::vector<double>& observed, int start);

/// A task's calibration, as stored in configs/calibration/<task>.json.
struct ResponseCalibration {
  std::string task;                ///< e.g. "pick_cube"
  TcpSlice slice;                  ///< where the TCP pose is in the observation
  LinearFit fit;                   ///< gains, noise, R²
  int episodes{0};                 ///< episodes of random actions
  int steps{0};                    ///< control steps per episode
  std::uint64_t seed{0};           ///< calibration seed
  std::string rotation_mode{"live"};  ///< how canonical rotation commands were applied (always live: unwrapped env)
  std::string profile{"maniskill"};   ///< simulator fidelity profile it was measured on
  std::string protocol{"maniskill_walk"};  ///< "maniskill_walk", "reference_walk" (8 walks x 64 steps) or "episodes"
  /// The finger channel, when calibrated (`calibrate --gripper-channel`). Optional key "gripper"
  /// of the JSON: a file without it serialises (and hashes) exactly as before.
  std::optional<GripperFit> gripper;

  ResponseModel model() const {
    ResponseModel m{fit.alpha, fit.sigma};
    if (gripper) {
      m.gripper_alpha = gripper->alpha;
      m.gripper_sigma = gripper->sigma;
    }
    return m;
  }
  /// Canonical JSON (sorted keys, Python-repr floats; schema "actionshift-calibration/2", which adds
  /// "profile" and "protocol" to /1; /1 files still load, as profile "ideal", protocol "episodes").
  std::string to_json() const;
  /// sha256 of to_json(): the calibration hash in job specs.
  std::string sha256() const;
  /// Parses and validates; throws InputError(source, field, reason).
  static ResponseCalibration from_json(const std::string& text, const std::string& source);
  static ResponseCalibration load(const std::string& path);
  /// load(path), refused unless it was measured for `task` on `profile` (another task's file would
  /// read the pose at that task's observation offsets; "maniskill[obs_noise=0.01]" counts as
  /// maniskill). `task_name` and `profile_name` say where the expected values came from in the
  /// messages ("the job's pick_cube", "--task pick_cube"). Throws InputError(path, field, reason).
  static ResponseCalibration load_for(const std::string& path, const std::string& task, const std::string& task_name,
                                      const std::string& profile, const std::string& profile_name);
};

}  // namespace actionshift::adapt
