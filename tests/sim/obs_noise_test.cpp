// observation (sensor) noise: off by default, only the TCP pose (and the tcp_to_* vectors) seen
// noisy, the simulated state untouched, a deterministic per-episode stream, bad settings rejected
#include "actionshift/sim/env.hpp"

#include "actionshift/core/rng.hpp"
#include "actionshift/sim/kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace actionshift::sim {
namespace {

std::shared_ptr<const EnvModel> model_with_noise(TaskId task, double sigma) {
  EnvConfig c = profile_config("maniskill");
  c.obs_noise = sigma;
  return EnvModel::make(task, c);
}

Action some_action(int t) {
  Action a = Action::Zero();
  a(0) = 0.5 * std::sin(0.3 * t);
  a(1) = 0.5 * std::cos(0.2 * t);
  a(2) = -0.3;
  a(5) = 0.4 * std::sin(0.1 * t);
  a(6) = t < 10 ? 1.0 : -1.0;
  return a;
}

struct Trace {
  std::vector<Eigen::VectorXd> obs;
  std::vector<Eigen::Isometry3d> tcp;  // the simulated (true) TCP pose
  std::vector<Eigen::VectorXd> objs;   // the true object pose observation field
};

Trace roll(const std::shared_ptr<const EnvModel>& m, std::uint64_t seed, int steps) {
  Env env(m);
  Trace t;
  t.obs.push_back(env.reset(seed));
  t.tcp.push_back(env.tcp_pose());
  for (int i = 0; i < steps; ++i) {
    t.obs.push_back(env.step(some_action(i)).obs);
    t.tcp.push_back(env.tcp_pose());
  }
  return t;
}

TEST(ObsNoise, OffByDefault) { EXPECT_EQ(EnvConfig{}.obs_noise, 0.0); EXPECT_EQ(profile_config("ideal").obs_noise, 0.0); }

TEST(ObsNoise, OnlyTheTcpPoseIsNoisyAndTheSimulationIsUntouched) {
  const double sigma = 0.01;
  const auto clean = model_with_noise(TaskId::kPickCube, 0.0);
  const auto noisy = model_with_noise(TaskId::kPickCube, sigma);
  const Trace a = roll(clean, 77, 30), b = roll(noisy, 77, 30);
  const ObservationLayout& l = clean->layout();
  const int p = l.at("tcp_pose").offset, q = p + 3, rel = l.at("tcp_to_obj_pos").offset;
  double sum2 = 0.0, rot2 = 0.0;
  int n = 0;
  for (std::size_t k = 0; k < a.obs.size(); ++k) {
    // the physics does not see the noise: the same actions give the same true state
    ASSERT_EQ(a.tcp[k].matrix(), b.tcp[k].matrix()) << "step " << k;
    for (int i = 0; i < l.size(); ++i) {
      const bool tcp_field = (i >= p && i < p + 7) || (i >= rel && i < rel + 3);
      if (!tcp_field) {
        ASSERT_EQ(a.obs[k](i), b.obs[k](i)) << "field index " << i << " step " << k;
      }
    }
    const Eigen::Vector3d d = b.obs[k].segment<3>(p) - a.obs[k].segment<3>(p);
    // tcp_to_obj_pos stays the object minus the observed TCP
    EXPECT_TRUE((b.obs[k].segment<3>(rel) + d).isApprox(a.obs[k].segment<3>(rel), 1e-12));
    sum2 += d.squaredNorm();
    n += 3;
    EXPECT_NEAR(b.obs[k].segment<4>(q).norm(), 1.0, 1e-12);
    EXPECT_GE(b.obs[k](q), 0.0);
    const Eigen::Matrix3d turn = quat_wxyz_to_rotation(b.obs[k].segment<4>(q)) * quat_wxyz_to_rotation(a.obs[k].segment<4>(q)).transpose();
    rot2 += so3_log(turn).squaredNorm();
  }
  // per-coordinate standard deviation near sigma (93 draws each; loose bounds)
  EXPECT_NEAR(std::sqrt(sum2 / n), sigma, 0.25 * sigma);
  EXPECT_NEAR(std::sqrt(rot2 / n), sigma, 0.25 * sigma);
}

TEST(ObsNoise, SameSeedSameNoiseAndOtherSeedsDiffer) {
  const auto noisy = model_with_noise(TaskId::kStackCube, 0.005);
  const Trace a = roll(noisy, 5, 10), b = roll(noisy, 5, 10), c = roll(noisy, 6, 10);
  for (std::size_t k = 0; k < a.obs.size(); ++k) ASSERT_EQ(a.obs[k], b.obs[k]);
  // reset draws fresh noise from the episode's seed, whatever ran before in the Env
  Env env(noisy);
  env.reset(6);
  for (int i = 0; i < 3; ++i) env.step(some_action(i));
  EXPECT_EQ(env.reset(5), a.obs[0]);
  // stack: both tcp_to_cube vectors move with the observed TCP
  const ObservationLayout& l = noisy->layout();
  const Eigen::VectorXd& o = a.obs[3];
  const Eigen::Vector3d tcp = o.segment<3>(l.at("tcp_pose").offset);
  EXPECT_TRUE((tcp + o.segment<3>(l.at("tcp_to_cubeA_pos").offset)).isApprox(o.segment<3>(l.at("cubeA_pose").offset), 1e-12));
  EXPECT_TRUE((tcp + o.segment<3>(l.at("tcp_to_cubeB_pos").offset)).isApprox(o.segment<3>(l.at("cubeB_pose").offset), 1e-12));
  EXPECT_NE(a.obs[0].segment<3>(l.at("tcp_pose").offset), c.obs[0].segment<3>(l.at("tcp_pose").offset));
}

TEST(ObsNoise, BadSettingsAreRejected) {
  for (double bad : {-0.001, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), kMaxObsNoise * 1.01}) {
    EnvConfig c;
    c.obs_noise = bad;
    EXPECT_THROW(EnvModel::make(TaskId::kPickCube, c), std::invalid_argument) << bad;
  }
  EnvConfig ok;
  ok.obs_noise = kMaxObsNoise;
  EXPECT_NO_THROW(EnvModel::make(TaskId::kPickCube, ok));
}

}  // namespace
}  // namespace actionshift::sim
