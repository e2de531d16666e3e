#pragma once
/// \file Fixed-size action and pose types shared by every layer.

#include <Eigen/Core>

namespace actionshift {

inline constexpr int kPoseDim = 6;    ///< pose channels: dx dy dz rx ry rz
inline constexpr int kActionDim = 7;  ///< pose channels + gripper
inline constexpr int kGripper = 6;    ///< index of the gripper channel

/// A raw or canonical action: translation delta (3), rotation vector delta (3), gripper (1),
/// in normalised units (±1 = ±0.1 m / ±0.1 rad per control step; gripper +1 open, −1 closed).
using Action = Eigen::Matrix<double, kActionDim, 1>;
/// A 6-vector pose (translation, rotation vector), e.g. the decoder's tracked target.
using Pose6 = Eigen::Matrix<double, kPoseDim, 1>;
using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
/// Jacobian of the canonical action with respect to the raw action.
using ActionJacobian = Eigen::Matrix<double, kActionDim, kActionDim>;

}  // namespace actionshift
