// Observation (sensor) noise on the TCP pose (EnvConfig::obs_noise)
#include "obs_noise.hpp"

#include "actionshift/sim/kinematics.hpp"

#include <string_view>

namespace actionshift::sim::detail {

void apply_obs_noise(const ObservationLayout& layout, double sigma, Rng& rng, Eigen::VectorXd& obs) {
  if (sigma == 0.0) return;
  const ObsField& tcp = layout.at("tcp_pose");
  Eigen::Vector3d dp, dr;
  for (int i = 0; i < 3; ++i) dp(i) = rng.normal(0.0, sigma);
  for (int i = 0; i < 3; ++i) dr(i) = rng.normal(0.0, sigma);
  obs.segment<3>(tcp.offset) += dp;
  const Eigen::Vector4d q = obs.segment<4>(tcp.offset + 3);
  obs.segment<4>(tcp.offset + 3) = matrix_to_quat_wxyz(so3_exp(dr) * quat_wxyz_to_rotation(q));
  for (const ObsField& f : layout.fields())
    if (f.width == 3 && std::string_view(f.name).starts_with("tcp_to_")) obs.segment<3>(f.offset) -= dp;
}

}  // namespace actionshift::sim::detail
