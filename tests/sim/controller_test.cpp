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

TEST(Controller, SingleStepIkIsOneDampedLeastSquaresStepWithoutClamping) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  const KinematicChain& arm = model->arm();
  Eigen::Matrix<double, 7, 1> q0;
  q0 << 0.1, 0.4, -0.1, -1.9, 0.05, 2.3, 0.8;
  Eigen::Matrix<double, 6, 1> a;
  a << 0.7, -0.3, 0.5, 0.2, -0.4, 0.9;
  const PoseCommand cmd = interpret_pose_command(a);
  const IkResult r = single_step_ik(arm, q0, cmd);
  Eigen::Isometry3d tip;
  ChainJacobian jac;
  arm.fk_jacobian(q0, tip, jac);
  Eigen::Matrix<double, 6, 1> dx;
  dx << cmd.delta_position, cmd.delta_rotvec;
  const Eigen::MatrixXd j = jac;
  const Eigen::VectorXd expected = q0 + (j.transpose() * j + 1e-4 * Eigen::MatrixXd::Identity(7, 7)).inverse() * j.transpose() * dx;
  EXPECT_LT((r.q - expected).norm(), 1e-9);
  EXPECT_EQ(r.iterations, 1);
  // a linear step leaves a first-order residual of ~0 but a real pose error after the move
  EXPECT_LT(r.error, 1e-3);
  EXPECT_GT((arm.fk(r.q).translation() - (tip.translation() + cmd.delta_position)).norm(), 1e-5);
  // at a joint limit the single step does not clamp (the simulator's limits act instead), the
  // converged solve does: search the six axis directions for one that pushes a joint past its limit
  Eigen::Matrix<double, 7, 1> qlim = q0;
  qlim(5) = arm.upper()(5) - 1e-4;
  bool beyond = false;
  for (int ch = 0; ch < 6 && !beyond; ++ch)
    for (double sgn : {-1.0, 1.0}) {
      Eigen::Matrix<double, 6, 1> c = Eigen::Matrix<double, 6, 1>::Zero();
      c(ch) = sgn;
      const IkResult one = single_step_ik(arm, qlim, interpret_pose_command(c));
      if ((one.q.array() > arm.upper().array()).any() || (one.q.array() < arm.lower().array()).any()) {
        beyond = true;
        const IkResult conv = solve_ik(arm, qlim, target_pose(arm.fk(qlim), interpret_pose_command(c)), IkOptions{IkMode::kConverged});
        EXPECT_TRUE((conv.q.array() <= arm.upper().array()).all() && (conv.q.array() >= arm.lower().array()).all());
        break;
      }
    }
  EXPECT_TRUE(beyond);
}

TEST(Profiles, NamesAndTheirSettings) {
  EXPECT_EQ(profile_names(), (std::vector<std::string>{"maniskill", "ideal"}));
  const EnvConfig m = profile_config("maniskill");
  EXPECT_EQ(m.profile, "maniskill");
  EXPECT_EQ(m.ik.mode, IkMode::kSingleStep);
  EXPECT_EQ(m.physics.arm_drive, ArmDrive::kImplicitPd);
  EXPECT_TRUE(m.physics.arm_joint_limits);
  EXPECT_EQ(EnvConfig{}.profile, std::string(kDefaultProfile));  // the default settings are the maniskill profile
  EXPECT_EQ(EnvConfig{}.ik.mode, m.ik.mode);
  EXPECT_EQ(EnvConfig{}.physics.arm_drive, m.physics.arm_drive);
  const EnvConfig i = profile_config("ideal");
  EXPECT_EQ(i.ik.mode, IkMode::kConverged);
  EXPECT_EQ(i.physics.arm_drive, ArmDrive::kVelocityServo);
  EXPECT_THROW(profile_config("physx"), std::invalid_argument);
}

// the maniskill profile's PD drive gives the arm inertia: after a command, a zero command (target =
// the current joints) does not stop it at once; the ideal servo stops where the next target is
TEST(Profiles, TheManiskillArmCarriesMomentumIntoTheNextStep) {
  for (const char* name : {"maniskill", "ideal"}) {
    Env env(EnvModel::make(TaskId::kPickCube, profile_config(name)));
    env.reset(5);
    Action a = Action::Zero();
    a(0) = 1.0;
    a(6) = 1.0;
    env.step(a);
    const Eigen::Vector3d p1 = env.tcp_pose_in_base().translation();
    a(0) = 0.0;
    env.step(a);
    const double coast = env.tcp_pose_in_base().translation().x() - p1.x();
    std::printf("[profile %s] x after a zero command following +1: %.5f m\n", name, coast);
    if (std::string(name) == "maniskill") {
      EXPECT_GT(coast, 0.0005);  // measured 0.8 mm: the joint-space inertia makes the PD mildly second order
    } else {
      EXPECT_LT(std::abs(coast), 0.002);
    }
  }
}

// one control step of +0.5 on each pose channel from the same seeded start: the TCP must move
// along that channel (base frame; rotation about the TCP). The maniskill profile's single IK step
// from the rest pose couples z into x (measured 30 % of the z motion), the converged IK does not.
TEST(Controller, EachPoseChannelMovesTheTcpInItsOwnDirection) {
 for (const auto& [name, cross_tolerance] : {std::pair<const char*, double>{"maniskill", 0.35}, {"ideal", 0.15}}) {
  std::printf("[profile %s]\n", name);
  const auto model = EnvModel::make(TaskId::kPickCube, profile_config(name));
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
    EXPECT_LT((moved - along * Eigen::Vector3d::Unit(ch % 3)).norm(), cross_tolerance * along) << name << " channel " << ch;
    if (ch >= 3) {
      EXPECT_LT(dp.norm(), 0.004) << "rotation must be about the TCP, channel " << ch;
    } else {
      EXPECT_LT(dr.norm(), 0.02) << "channel " << ch;
    }
  }
 }
}

}  // namespace
}  // namespace actionshift::sim
