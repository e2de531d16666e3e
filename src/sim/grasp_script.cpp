// scripted grasp-and-lift on the true object pose
#include "actionshift/sim/grasp_script.hpp"

#include "actionshift/sim/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace actionshift::sim {
namespace {

// desired hand orientation: pointing down, yaw aligned with the nearest face pair of the object
Eigen::Matrix3d aligned_rotation(const Eigen::Matrix3d& tcp, const Eigen::Matrix3d& obj) {
  const double hand_yaw = std::atan2(tcp(1, 0), tcp(0, 0));
  const double obj_yaw = std::atan2(obj(1, 0), obj(0, 0));
  // the gripper is symmetric under a quarter turn of a cube: pick the closest multiple of pi/2
  double d = std::remainder(obj_yaw - hand_yaw, std::numbers::pi / 2);
  const double yaw = hand_yaw + d;
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // hand x = world x, hand z = world -z
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * down;
}

Action move_to(const Eigen::Isometry3d& tcp, const Eigen::Vector3d& p, const Eigen::Matrix3d& r, double gripper) {
  constexpr double kGain = 2.0;  // the arm achieves about half of a command per step (docs/sim.md)
  Action a;
  a.head<3>() = (kGain * (p - tcp.translation()) / 0.1).cwiseMax(-1.0).cwiseMin(1.0);
  Eigen::Vector3d rv = kGain * so3_log(r * tcp.linear().transpose()) / 0.1;
  if (rv.norm() > 1.0) rv.normalize();
  a.segment<3>(3) = rv;
  a(6) = gripper;
  return a;
}

}  // namespace

Action GraspLiftScript::act(const TaskSnapshot& s) {
  const Eigen::Vector3d obj = s.obj[0].translation();
  const Eigen::Isometry3d& tcp = s.tcp;
  ++phase_steps_;
  switch (phase_) {
    case Phase::kApproach: {
      const Eigen::Matrix3d r = aligned_rotation(tcp.linear(), s.obj[0].linear());
      const Eigen::Vector3d above = obj + Eigen::Vector3d(0, 0, 0.05);
      const double err = (above - tcp.translation()).norm() + so3_log(r * tcp.linear().transpose()).norm() * 0.05;
      if (err < 0.006 || phase_steps_ > 25) {
        phase_ = Phase::kDescend;
        phase_steps_ = 0;
        hold_rotation_ = r;
      }
      return move_to(tcp, above, r, 1.0);
    }
    case Phase::kDescend: {
      const Eigen::Vector3d at = obj;
      if ((at - tcp.translation()).norm() < 0.004 || phase_steps_ > 15) {
        phase_ = Phase::kClose;
        phase_steps_ = 0;
        grasp_xy_ = tcp.translation().head<2>();
        grasp_z_ = tcp.translation().z();
      }
      return move_to(tcp, at, hold_rotation_, 1.0);
    }
    case Phase::kClose: {
      if (phase_steps_ >= 5) {
        phase_ = Phase::kLift;
        phase_steps_ = 0;
        grasp_offset_ = tcp.inverse() * obj;
      }
      return move_to(tcp, Eigen::Vector3d(grasp_xy_.x(), grasp_xy_.y(), grasp_z_), hold_rotation_, -1.0);
    }
    case Phase::kLift:
    case Phase::kHold: {
      const Eigen::Vector3d up(grasp_xy_.x(), grasp_xy_.y(), grasp_z_ + lift_height_);
      if (phase_ == Phase::kLift && (up - tcp.translation()).norm() < 0.003) phase_ = Phase::kHold;
      return move_to(tcp, up, hold_rotation_, -1.0);
    }
  }
  return Action::Zero();
}

}  // namespace actionshift::sim
