#pragma once
/// \file The observable response of the robot to an action, and the calibrated Gaussian response
/// model adapters use as likelihood (docs/reference.md, *Calibration and the response model*).
///
/// response = [TCP translation (world/base axes, m), rotation vector of q_cur ⊗ conj(q_prev) (rad)]
/// between two consecutive observations. The calibrated model predicts response_c ≈ α_c·canonical_c
/// with Gaussian noise σ_c per pose channel.

#include "actionshift/core/types.hpp"

#include <Eigen/Core>

#include <array>
#include <span>
#include <string>

namespace actionshift::adapt {

/// Hamilton product of two (w, x, y, z) quaternions.
Eigen::Vector4d quat_multiply(const Eigen::Vector4d& l, const Eigen::Vector4d& r);
/// Rotation vector of a (w, x, y, z) quaternion (normalised first; reference `quat_to_rotvec`).
Vec3 quat_to_rotvec(const Eigen::Vector4d& q);

/// Where the TCP pose sits in a flat observation vector.
struct TcpSlice {
  int position_start{-1};    ///< offset of x y z [m]
  int quaternion_start{-1};  ///< offset of w x y z
};

/// TCP response between two observations: translation (3) then relative rotation vector (3).
/// Throws std::invalid_argument if the slice does not fit the observations.
Pose6 tcp_response(std::span<const double> prev_obs, std::span<const double> cur_obs, const TcpSlice& slice);

/// Orientation matrix of the TCP in an observation (the frame rotation adapters feed to decoders).
Mat3 tcp_rotation(std::span<const double> obs, const TcpSlice& slice);

inline std::span<const double> as_span(const Eigen::VectorXd& v) {
  return {v.data(), static_cast<std::size_t>(v.size())};
}
inline Pose6 tcp_response(const Eigen::VectorXd& prev, const Eigen::VectorXd& cur, const TcpSlice& slice) {
  return tcp_response(as_span(prev), as_span(cur), slice);
}
inline Mat3 tcp_rotation(const Eigen::VectorXd& obs, const TcpSlice& slice) { return tcp_rotation(as_span(obs), slice); }

/// Calibrated per-channel Gaussian response model.
struct ResponseModel {
  std::array<double, kPoseDim> alpha{1, 1, 1, 1, 1, 1};  ///< response per unit canonical command (m or rad)
  std::array<double, kPoseDim> sigma{1, 1, 1, 1, 1, 1};  ///< noise std of the response (m or rad), > 0
  /// Optional seventh channel (the reference's "v2 finger evidence"): the mean finger-position
  /// change per step ≈ gripper_alpha · canonical gripper command, noise gripper_sigma [m].
  /// gripper_sigma == 0 means the channel is not calibrated.
  double gripper_alpha{0.0};
  double gripper_sigma{0.0};

  bool has_gripper() const noexcept { return gripper_sigma > 0.0; }

  /// Throws std::invalid_argument unless every α is finite and non-zero and every σ finite > 0
  /// (and, with a finger channel, its α finite and non-zero and its σ finite > 0).
  void validate() const;

  /// α ⊙ canonical pose.
  Pose6 expected(const Action& canonical) const {
    Pose6 e;
    for (int c = 0; c < kPoseDim; ++c) e[c] = alpha[static_cast<std::size_t>(c)] * canonical[c];
    return e;
  }
  /// −½ Σ_c ((observed_c − α_c·predicted_c)/σ_c)², without the normalising constant.
  double log_likelihood(const Action& predicted_canonical, const Pose6& observed) const {
    double s = 0.0;
    for (int c = 0; c < kPoseDim; ++c) {
      const auto k = static_cast<std::size_t>(c);
      const double r = (observed[c] - alpha[k] * predicted_canonical[c]) / sigma[k];
      s += r * r;
    }
    return -0.5 * s;
  }
};

}  // namespace actionshift::adapt
