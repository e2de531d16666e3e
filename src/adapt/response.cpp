#include "actionshift/adapt/response.hpp"

#include "actionshift/core/transforms.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace actionshift::adapt {

Eigen::Vector4d quat_multiply(const Eigen::Vector4d& l, const Eigen::Vector4d& r) {
  return {l[0] * r[0] - l[1] * r[1] - l[2] * r[2] - l[3] * r[3],
          l[0] * r[1] + l[1] * r[0] + l[2] * r[3] - l[3] * r[2],
          l[0] * r[2] - l[1] * r[3] + l[2] * r[0] + l[3] * r[1],
          l[0] * r[3] + l[1] * r[2] - l[2] * r[1] + l[3] * r[0]};
}

Vec3 quat_to_rotvec(const Eigen::Vector4d& q_in) {
  const Eigen::Vector4d q = q_in / std::max(q_in.norm(), 1e-12);
  const double w = std::clamp(q[0], -1.0, 1.0);
  const Vec3 v = q.tail<3>();
  const double angle = 2.0 * std::acos(std::abs(w));
  const double s = w < 0 ? -1.0 : 1.0;
  return s * v / std::max(v.norm(), 1e-12) * angle;
}

namespace {
void check_slice(std::span<const double> obs, const TcpSlice& s) {
  if (s.position_start < 0 || s.quaternion_start < 0 || static_cast<std::size_t>(s.position_start + 3) > obs.size() ||
      static_cast<std::size_t>(s.quaternion_start + 4) > obs.size())
    throw std::invalid_argument("TCP slice (position " + std::to_string(s.position_start) + ", quaternion " +
                                std::to_string(s.quaternion_start) + ") does not fit an observation of size " +
                                std::to_string(obs.size()));
}
Eigen::Vector4d quat_at(std::span<const double> obs, int start) {
  const auto k = static_cast<std::size_t>(start);
  return {obs[k], obs[k + 1], obs[k + 2], obs[k + 3]};
}
}  // namespace

Pose6 tcp_response(std::span<const double> prev, std::span<const double> cur, const TcpSlice& s) {
  check_slice(prev, s);
  check_slice(cur, s);
  Pose6 r;
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(s.position_start + i);
    r[i] = cur[k] - prev[k];
  }
  Eigen::Vector4d conj = quat_at(prev, s.quaternion_start);
  conj.tail<3>() *= -1.0;
  r.tail<3>() = quat_to_rotvec(quat_multiply(quat_at(cur, s.quaternion_start), conj));
  return r;
}

Mat3 tcp_rotation(std::span<const double> obs, const TcpSlice& s) {
  check_slice(obs, s);
  return quat_wxyz_to_matrix(quat_at(obs, s.quaternion_start));
}

void ResponseModel::validate() const {
  for (int c = 0; c < kPoseDim; ++c) {
    const auto k = static_cast<std::size_t>(c);
    if (!std::isfinite(alpha[k]) || alpha[k] == 0.0)
      throw std::invalid_argument("response model: alpha[" + std::to_string(c) + "] must be finite and non-zero");
    if (!std::isfinite(sigma[k]) || sigma[k] <= 0.0)
      throw std::invalid_argument("response model: sigma[" + std::to_string(c) + "] must be finite and positive");
  }
  if (!std::isfinite(gripper_sigma) || gripper_sigma < 0.0)
    throw std::invalid_argument("response model: gripper_sigma must be finite and nonnegative");
  if (has_gripper() && (!std::isfinite(gripper_alpha) || gripper_alpha == 0.0))
    throw std::invalid_argument("response model: gripper_alpha must be finite and non-zero");
}

}  // namespace actionshift::adapt
