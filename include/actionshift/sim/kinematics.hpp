#pragma once
/// \file
/// Serial-chain forward kinematics and geometric Jacobians (Eigen), built from a RobotDescription,
/// plus the small SO(3) helpers the controller and observations use.

#include "actionshift/sim/robot_description.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string_view>
#include <vector>

namespace actionshift::sim {

inline constexpr int kMaxChainDof = 16;
/// Joint vector of a chain (no heap allocation, at most kMaxChainDof entries).
using ChainVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxChainDof, 1>;
/// 6 x dof geometric Jacobian: rows 0-2 linear velocity of the tip point, rows 3-5 angular velocity,
/// both in the chain root frame.
using ChainJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxChainDof>;

/// The movable joints from the root link to a tip frame, with the fixed transforms between them.
class KinematicChain {
 public:
  KinematicChain() = default;
  /// Chain from `desc.root` to link `tip`. throws std::out_of_range if the link is absent,
  /// std::invalid_argument if the chain has more than kMaxChainDof movable joints.
  KinematicChain(const RobotDescription& desc, std::string_view tip);

  int dof() const { return static_cast<int>(steps_.size()); }
  /// Description joint index of each chain dof, root to tip.
  const std::vector<int>& joint_indices() const { return joint_indices_; }
  const ChainVector& lower() const { return lower_; }  ///< joint lower limits
  const ChainVector& upper() const { return upper_; }  ///< joint upper limits

  /// Tip pose in the root frame. q has dof() entries.
  Eigen::Isometry3d fk(const Eigen::Ref<const Eigen::VectorXd>& q) const;
  /// Tip pose and geometric Jacobian at q (allocation-free).
  void fk_jacobian(const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Isometry3d& tip, ChainJacobian& jac) const;

 private:
  struct Step {
    Eigen::Matrix3d rot;    // fixed rotation from the previous joint frame to this joint frame
    Eigen::Vector3d trans;  // fixed translation, previous joint frame
    Eigen::Vector3d axis;   // joint axis in this joint frame
    bool prismatic{false};
  };
  std::vector<Step> steps_;
  Eigen::Matrix3d tail_rot_{Eigen::Matrix3d::Identity()};
  Eigen::Vector3d tail_trans_{Eigen::Vector3d::Zero()};
  std::vector<int> joint_indices_;
  ChainVector lower_, upper_;
};

/// Rotation matrix of a rotation vector (axis * angle).
Eigen::Matrix3d so3_exp(const Eigen::Vector3d& rotvec);
/// Rotation vector of a rotation matrix (angle in [0, pi]).
Eigen::Vector3d so3_log(const Eigen::Matrix3d& r);
/// Quaternion (w, x, y, z) of a rotation matrix, with w >= 0 for a unique representation.
Eigen::Vector4d matrix_to_quat_wxyz(const Eigen::Matrix3d& r);
/// Rotation matrix of a quaternion (w, x, y, z); the quaternion is normalised first.
Eigen::Matrix3d quat_wxyz_to_rotation(const Eigen::Vector4d& q);

/// Franka modified-DH flange (link8) pose for the 7 arm joints (facts section 4.2); reference for tests.
Eigen::Isometry3d franka_dh_flange(const Eigen::Matrix<double, 7, 1>& q);

}  // namespace actionshift::sim
