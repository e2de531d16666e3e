#pragma once
/// \file Response calibration on the unwrapped simulator (docs/reference.md, *Calibration and the response model*): random canonical
/// actions, the TCP response of each step, and a per-channel linear fit.

#include "actionshift/adapt/calibration.hpp"
#include "actionshift/sim/env.hpp"

#include <cstdint>
#include <memory>

namespace actionshift::eval {

/// How the random actions are laid out.
enum class CalibrationProtocol {
  /// The public reference implementation's protocol as it runs in ManiSkill: `episodes` random walks
  /// (8 environments) of `steps` control steps (64), uniform actions in [-1, 1] on all 7 channels
  /// (gripper included), in the task's own episodes: the walk is truncated at the task's horizon (50
  /// for the cube tasks) and the environment resets there, as ManiSkill's vector wrapper auto-resets
  /// (ignore_terminations, every environment ends together), so the response paired with the action
  /// of the step that crosses the horizon is the jump from the walk's end to the fresh episode's start.
  /// The response of step k-1 -> k is paired with action k: 8 x 63 = 504 samples. No workspace stop.
  kManiSkillWalk,
  /// The same walks read without the time limit: no reset and no horizon inside a walk (what the
  /// project used before it found the auto-reset; kept for the ablation).
  kReferenceWalk,
  /// The project's earlier protocol: `episodes` task episodes (16) of at most `steps` (50, capped at
  /// the horizon), each reset, ended early by a safety check; every step gives a sample.
  kEpisodes,
};

/// Name of a protocol as recorded in calibration files: "maniskill_walk", "reference_walk" or "episodes".
std::string_view protocol_name(CalibrationProtocol p);
/// Inverse of protocol_name; throws std::invalid_argument naming the known protocols.
CalibrationProtocol parse_protocol(std::string_view name);

struct CalibrationOptions {
  CalibrationProtocol protocol{CalibrationProtocol::kManiSkillWalk};
  int episodes{8};                  ///< random walks (reference: 8 environments) or episodes
  int steps{64};                    ///< control steps per walk (reference: 64) or per episode
  std::uint64_t seed{20260720};     ///< the reference's calibration seed
  /// Also fit the finger channel (the public reference implementation's finger channel, docs/reference.md): gripper action vs the change of the mean of the
  /// two finger joint positions (qpos[7:9]) over each step. Adds the optional "gripper" key.
  bool gripper_channel{false};
};

/// Offset of the two finger joint positions in a task's observation (qpos[7], qpos[8]).
/// Throws std::invalid_argument if the layout has no 9-wide qpos field.
int finger_start(const sim::ObservationLayout& layout);

/// Where the TCP pose is in a task's observation ("tcp_pose": position xyz then quaternion wxyz).
/// Throws std::invalid_argument if the layout has no 7-wide tcp_pose field.
adapt::TcpSlice tcp_slice(const sim::ObservationLayout& layout);

/// The one check that a calibration fits a task's observation (used by `run`, `selftest --sim` and
/// Python): its TCP position and quaternion offsets, and its finger channel's offset if it has one,
/// must be where `layout` has them. Throws InputError(source, field, …) naming the offset.
void check_calibration_layout(const adapt::ResponseCalibration& cal, const sim::ObservationLayout& layout,
                              const std::string& task, const std::string& source);

/// Runs the calibration on the model's fidelity profile: walk/episode e resets with
/// derive_seed({seed, e}) and draws uniform actions in [-1, 1]^7 from Rng(derive_seed({seed, e, 1}));
/// each response is paired with its action as the protocol says. Deterministic in (model, options).
adapt::ResponseCalibration calibrate(std::shared_ptr<const sim::EnvModel> model, const CalibrationOptions& options = {});

}  // namespace actionshift::eval
