#pragma once
/// \file
/// Small Cartesian helpers shared by the scripted experts (implementation detail).

#include "actionshift/core/types.hpp"
#include "actionshift/sim/kinematics.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>

namespace actionshift::policy::detail {

/// Yaw of a hand pointing down: heading of its x axis in the world xy plane [rad].
inline double yaw_of(const Eigen::Matrix3d& r) { return std::atan2(r(1, 0), r(0, 0)); }

/// Hand pointing down (hand z = world -z) with yaw `yaw` [rad].
inline Eigen::Matrix3d down_rotation(double yaw) {
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * down;
}

/// Hand pointing down with its yaw on a face pair of the cube (a cube is symmetric under quarter
/// turns): the representative within +-pi/4 of the fixed reference yaw `ref_yaw` [rad] (the task's
/// rest hand yaw). The target depends on the cube alone, not on the moving hand, so it does not
/// chase the hand as it turns (a learner imitating it cannot spin past it).
inline Eigen::Matrix3d cube_grasp_rotation(double ref_yaw, const Eigen::Matrix3d& cube) {
  return down_rotation(ref_yaw + std::remainder(yaw_of(cube) - ref_yaw, std::numbers::pi / 2));
}

/// Proportional move of the TCP towards position `p` [m] and orientation `r` (world = base axes):
/// canonical units are 0.1 m / 0.1 rad per step; the arm achieves roughly half of a command per
/// step, hence the default gain 2. Translation is clipped per component to `max_trans` (<= 1),
/// the rotation vector to norm 1.
inline Action move_to(const Eigen::Isometry3d& tcp, const Eigen::Vector3d& p, const Eigen::Matrix3d& r, double gripper,
                      double gain = 2.0, double max_trans = 1.0) {
  Action a;
  a.head<3>() = (gain * (p - tcp.translation()) / 0.1).cwiseMax(-max_trans).cwiseMin(max_trans);
  Eigen::Vector3d rv = gain * sim::so3_log(r * tcp.linear().transpose()) / 0.1;
  if (rv.norm() > 1.0) rv.normalize();
  a.segment<3>(3) = rv;
  a(6) = gripper;
  return a;
}

}  // namespace actionshift::policy::detail
