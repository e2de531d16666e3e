// pd_ee_delta_pose: clipping, ik, and the measured response of every pose channel
#include "actionshift/sim/controller.hpp"
#include "actionshift/sim/env.hpp"

#include "actionshift/core/rng.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace actionshift::sim {
namespace {

TEST(Controller, ClipsTranslationPerComponentAndRotationByNorm) {
  Eigen::Matrix<double, 6, 1> a;
  a << 2.0, -0.5, -3.0, 3.0, 4.0, 0.0;
  const PoseCommand c = interpret_pose_command(a);
  EXPECT_TRUE(c.clipped);
  EXPECT_TRUE(c.delta_position.isApprox(Eigen::Vector3d(0.1, -0.05, -0.1)));
  EXPECT_TRUE(c.delta_rotvec.isApprox(Eigen::Vector3d(0.06, 0.08, 0.0)));  // norm 5 -> 1, no sign flip
  a << 0.5, 0.5, 0.5, 0.3, 0.0, 0.0;
  EXPECT_FALSE(interpret_pose_command(a).clipped);
  EXPECT_DOUBLE_EQ(finger_target(1.0), 0.04);
  EXPECT_DOUBLE_EQ(finger_target(-1.0), -0.01);
  EXPECT_DOUBLE_EQ(finger_target(-7.0), -0.01);
  EXPECT_DOUBLE_EQ(finger_target(0.0), 0.015);
}

TEST(Controller, TargetRotatesAboutTheTcpWithBaseAlignedAxes) {
  Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
  tcp.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  tcp.translation() = Eigen::Vector3d(0.5, 0.1, 0.3);
  Eigen::Matrix<double, 6, 1> a = Eigen::Matrix<double, 6, 1>::Zero();
  a(5) = 1.0;
  const Eigen::Isometry3d t = target_pose(tcp, interpret_pose_command(a));
  EXPECT_TRUE(t.translation().isApprox(tcp.translation()));
  EXPECT_TRUE(t.linear().isApprox(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix() * tcp.linear()));
}

TEST(Controller, DampedLeastSquaresIkReachesNearbyTargetsWithinLimits) {
  const KinematicChain arm(panda_description(), "panda_hand_tcp");
  Rng rng(3);
  // configurations around the task workspace (rest pose +- 0.4 rad), any command in [-1, 1]^6
  Eigen::Matrix<double, 7, 1> rest;
  rest << 0, 0.3927, 0, -1.9635, 0, 2.3562, 0.7854;
  for (int n = 0; n < 200; ++n) {
    Eigen::Matrix<double, 7, 1> q;
    for (int i = 0; i < 7; ++i) q(i) = rest(i) + rng.uniform(-0.4, 0.4);
    Eigen::Matrix<double, 6, 1> a;
    for (int i = 0; i < 6; ++i) a(i) = rng.uniform(-1, 1);
    const Eigen::Isometry3d target = target_pose(arm.fk(q), interpret_pose_command(a));
    const IkResult r = solve_ik(arm, q, target);
    EXPECT_LT(r.error, 1e-8) << "config " << n;
    EXPECT_TRUE((r.q.array() >= arm.lower().array()).all() && (r.q.array() <= arm.upper().array()).all());
  }
  // an unreachable target: best effort, limits still respected
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Eigen::Vector3d(3, 0, 0);
  const IkResult r = solve_ik(arm, Eigen::Matrix<double, 7, 1>::Zero(), far);
  EXPECT_GT(r.error, 1.0);
  EXPECT_TRUE((r.q.array() >= arm.lower().array()).all() && (r.q.array() <= arm.upper().array()).all());
}

// one control step of +0.5 on each pose channel from the same seeded start: the TCP must move
// along that channel (base frame; rotation about the TCP)
TEST(Controller, EachPoseChannelMovesTheTcpInItsOwnDirection) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  Env env(model);
  for (int ch = 0; ch < 6; ++ch) {
    env.reset(11);
    const Eigen::Isometry3d before = env.tcp_pose_in_base();
    Action a = Action::Zero();
    a(ch) = 0.5;
    a(6) = 1.0;
    env.step(a);
    const Eigen::Isometry3d after = env.tcp_pose_in_base();
    const Eigen::Vector3d dp = after.translation() - before.translation();
    const Eigen::Vector3d dr = so3_log(after.linear() * before.linear().transpose());
    const Eigen::Vector3d moved = ch < 3 ? dp : dr;
    const double along = moved(ch % 3);
    std::printf("[response] channel %d: %.5f %s per 0.5 command in one step (cross %.5f, other %.5f)\n", ch, along,
                ch < 3 ? "m" : "rad", (moved - along * Eigen::Vector3d::Unit(ch % 3)).norm(), ch < 3 ? dr.norm() : dp.norm());
    EXPECT_GT(along, 0.01) << "channel " << ch;
    EXPECT_LT((moved - along * Eigen::Vector3d::Unit(ch % 3)).norm(), 0.15 * along) << "channel " << ch;
    if (ch >= 3) {
      EXPECT_LT(dp.norm(), 0.004) << "rotation must be about the TCP, channel " << ch;
    } else {
      EXPECT_LT(dr.norm(), 0.02) << "channel " << ch;
    }
  }
}

}  // namespace
}  // namespace actionshift::sim
