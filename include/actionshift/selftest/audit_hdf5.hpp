#pragma once
/// \file HDF5 logs for the audit (docs/audit.md, "Formats"): ManiSkill's trajectory layout and
/// robomimic's dataset layout. Target ActionShift::selftest_hdf5 (HDF5's C API, in one translation
/// unit), kept apart from ActionShift::selftest so that the self-test library needs no HDF5.

#include "actionshift/selftest/audit.hpp"

#include <string>

namespace actionshift::selftest {

/// Reads either layout (detected from the file's groups):
/// - ManiSkill: `traj_N/actions` (T × 7, or T × 6, or T × 4 for pd_ee_delta_pos), the TCP pose in
///   `traj_N/obs/extra/tcp_pose` (T + 1 × 7: x y z qw qx qy qz; state_dict observations), finger
///   positions from the last two columns of `traj_N/obs/agent/qpos` if present; the JSON sidecar
///   (same name, .json) gives `control_mode`, which becomes the log's declaration (pd_ee_delta_pose:
///   delta, base, XYZ Euler rotation deltas; pd_ee_pose: the action is the next state; joint-space
///   modes are refused).
/// - robomimic: `data/demo_N/actions` (T × 7), `data/demo_N/obs/robot0_eef_pos` (T × 3),
///   `robot0_eef_quat` (T × 4, x y z w), `robot0_gripper_qpos` (T × 2; the second finger's sign is
///   flipped, so both open positive), `next_obs/…` (optional: the final pose); `data` attribute
///   `env_args` (JSON, a variable-length or fixed-length string): robosuite's OSC_POSE or OSC_POSITION
///   arm controller with delta input (the config itself before robosuite 1.5, a composite
///   controller's arm part from 1.5) declares delta, base, axis-angle, gripper −1 open; absolute
///   input and other controllers declare nothing, and `declared_from` says why.
/// Throws InputError(path, "<dataset path>", reason) for anything else.
ActionLog read_log_hdf5(const std::string& path);

/// read_log_hdf5 for .h5/.hdf5 names, read_log_text otherwise.
ActionLog read_log(const std::string& path);

/// Writes `log` in ManiSkill's layout (float32 datasets, as ManiSkill writes them) plus the JSON
/// sidecar `<path without .h5>.json` with `control_mode`. Atomic per file.
void write_log_maniskill(const ActionLog& log, const std::string& path, const std::string& control_mode = "pd_ee_delta_pose");
/// Writes `log` in robomimic's layout (float64), with `env_args` naming `controller` (e.g. "OSC_POSE").
void write_log_robomimic(const ActionLog& log, const std::string& path, const std::string& controller = "OSC_POSE");

}  // namespace actionshift::selftest
