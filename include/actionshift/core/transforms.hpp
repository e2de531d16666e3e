#pragma once
/// \file Pure decode/encode of one action under a contract (docs/semantics.md §3; docs/reference.md, *Contracts*).
///
/// decode: raw → permutation → sign·scale (indexed by output channel) → frame (tool: rotate the
/// translation and the rotation vector by R, the live TCP orientation read before the step) →
/// target (absolute: the decoded pose is the new tracked target; the canonical delta is new target
/// − previous tracked target) → gripper inversion. The lag FIFO is stateful: see Decoder.
/// encode is the exact inverse given the same R and tracked target. Raw actions are never clamped.

#include "actionshift/core/contract.hpp"
#include "actionshift/core/types.hpp"

#include <Eigen/Core>

#include <cmath>
#include <string>

namespace actionshift {

/// Pose part only: decoded[i] = raw[perm[i]] · sign[i] · scale[i].
inline Pose6 decode_pose(const Contract& c, const Pose6& raw) {
  Pose6 out;
  const auto& p = c.permutation();
  const auto& g = c.gain();
  for (int i = 0; i < kPoseDim; ++i) out[i] = raw[p[static_cast<std::size_t>(i)]] * g[static_cast<std::size_t>(i)];
  return out;
}

/// Inverse of decode_pose: raw[perm[i]] = pose[i] / (sign[i] · scale[i]).
inline Pose6 encode_pose(const Contract& c, const Pose6& pose) {
  Pose6 raw;
  const auto& p = c.permutation();
  const auto& g = c.gain();
  for (int i = 0; i < kPoseDim; ++i) raw[p[static_cast<std::size_t>(i)]] = pose[i] / g[static_cast<std::size_t>(i)];
  return raw;
}

/// True if R is a proper rotation (finite, RᵀR ≈ I with rtol 1e-5 / atol 1e-6, det > 0), as the
/// reference's precondition. Fills `*why` on failure.
inline bool is_rotation(const Mat3& R, std::string* why = nullptr) {
  if (!R.allFinite()) {
    if (why) *why = "rotation matrix is not finite";
    return false;
  }
  const Mat3 e = R.transpose() * R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double want = i == j ? 1.0 : 0.0;
      if (std::abs(e(i, j) - want) > 1e-6 + 1e-5 * std::abs(want)) {
        if (why) *why = "rotation matrix is not orthonormal";
        return false;
      }
    }
  const double det = R(0, 0) * (R(1, 1) * R(2, 2) - R(1, 2) * R(2, 1)) - R(0, 1) * (R(1, 0) * R(2, 2) - R(1, 2) * R(2, 0)) +
                     R(0, 2) * (R(1, 0) * R(2, 1) - R(1, 1) * R(2, 0));
  if (det <= 0.0) {
    if (why) *why = "rotation matrix has non-positive determinant";
    return false;
  }
  return true;
}

/// Decodes one raw action (before lag). `tracked_target` is the previous decoded target;
/// `next_target` (if non-null) receives the updated one. R is only read for `frame == tool`.
/// Allocation-free.
inline Action decode(const Contract& c, const Action& raw, const Mat3& R, const Pose6& tracked_target,
                     Pose6* next_target = nullptr) {
  const auto& p = c.permutation();
  const auto& g = c.gain();
  Vec3 t(raw[p[0]] * g[0], raw[p[1]] * g[1], raw[p[2]] * g[2]);
  Vec3 r(raw[p[3]] * g[3], raw[p[4]] * g[4], raw[p[5]] * g[5]);
  if (c.frame() == Frame::kTool) {
    t = R * t;
    r = R * r;
  }
  Action out;
  if (c.target() == Target::kAbsolute) {
    out.head<3>() = t - tracked_target.head<3>();
    out.segment<3>(3) = r - tracked_target.tail<3>();
    if (next_target) *next_target << t, r;
  } else {
    out.head<3>() = t;
    out.segment<3>(3) = r;
    if (next_target) *next_target = tracked_target + out.head<kPoseDim>();
  }
  out[kGripper] = c.gripper_inverted() ? -raw[kGripper] : raw[kGripper];
  return out;
}

/// Exact inverse of decode(): the raw action that decodes to `canonical` under the same R and
/// tracked target (the oracle's path).
inline Action encode(const Contract& c, const Action& canonical, const Mat3& R, const Pose6& tracked_target) {
  Vec3 t = canonical.head<3>();
  Vec3 r = canonical.segment<3>(3);
  if (c.target() == Target::kAbsolute) {
    t += tracked_target.head<3>();
    r += tracked_target.tail<3>();
  }
  if (c.frame() == Frame::kTool) {
    t = R.transpose() * t;
    r = R.transpose() * r;
  }
  const auto& p = c.permutation();
  const auto& g = c.gain();
  Action raw;
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    raw[p[k]] = t[i] / g[k];
    raw[p[k + 3]] = r[i] / g[k + 3];
  }
  raw[kGripper] = c.gripper_inverted() ? -canonical[kGripper] : canonical[kGripper];
  return raw;
}

/// ∂canonical/∂raw of decode(). Decode is affine in the raw action, so the Jacobian depends only
/// on the contract and R (not on the raw action or the tracked target): row i of the pose block is
/// gain[i]·e_{perm[i]}, rotated by blockdiag(R, R) for the tool frame; the gripper entry is ±1.
inline ActionJacobian decode_jacobian(const Contract& c, const Mat3& R = Mat3::Identity()) {
  Eigen::Matrix<double, kPoseDim, kPoseDim> P = Eigen::Matrix<double, kPoseDim, kPoseDim>::Zero();
  for (int i = 0; i < kPoseDim; ++i)
    P(i, c.permutation()[static_cast<std::size_t>(i)]) = c.gain()[static_cast<std::size_t>(i)];
  if (c.frame() == Frame::kTool) {
    P.topRows<3>() = R * P.topRows<3>().eval();
    P.bottomRows<3>() = R * P.bottomRows<3>().eval();
  }
  ActionJacobian J = ActionJacobian::Zero();
  J.topLeftCorner<kPoseDim, kPoseDim>() = P;
  J(kGripper, kGripper) = c.gripper_inverted() ? -1.0 : 1.0;
  return J;
}

/// Quaternion (w, x, y, z) to rotation matrix; the quaternion is normalised (norm clamped ≥ 1e-12)
/// as the reference's `quaternion_to_rotation_matrix`.
inline Mat3 quat_wxyz_to_matrix(const Eigen::Vector4d& q_in) {
  const Eigen::Vector4d q = q_in / std::max(q_in.norm(), 1e-12);
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  Mat3 R;
  R << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),   //
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
  return R;
}

}  // namespace actionshift
