#pragma once
/// \file
/// A privileged scripted grasp-and-lift (reads the true object pose): the contact-rich motion the
/// `bench env` command times and the issue-3 grasp test runs. Not a policy (see the policy layer).

#include "actionshift/core/types.hpp"
#include "actionshift/sim/task.hpp"

#include <Eigen/Geometry>

namespace actionshift::sim {

/// Approach above the first object, align the hand yaw with its faces, descend, close, lift.
class GraspLiftScript {
 public:
  enum class Phase { kApproach, kDescend, kClose, kLift, kHold };

  /// `lift_height` [m]: how far above the grasp height the TCP is lifted.
  explicit GraspLiftScript(double lift_height = 0.15) : lift_height_(lift_height) {}

  /// Canonical action for the current state (call once per control step).
  Action act(const TaskSnapshot& s);
  Phase phase() const { return phase_; }
  /// TCP-frame position of the object when the lift started (slip reference); valid from kLift on.
  const Eigen::Vector3d& grasp_offset() const { return grasp_offset_; }
  double grasp_height() const { return grasp_z_; }

 private:
  double lift_height_;
  Phase phase_{Phase::kApproach};
  int phase_steps_{0};
  Eigen::Vector3d grasp_offset_{Eigen::Vector3d::Zero()};
  Eigen::Vector2d grasp_xy_{Eigen::Vector2d::Zero()};
  double grasp_z_{0.0};
  Eigen::Matrix3d hold_rotation_{Eigen::Matrix3d::Identity()};
};

}  // namespace actionshift::sim
