// the hand-built bullet articulation: its kinematics agree with the eigen chain, gravity is
// compensated, the mimic fingers move together (private header, no bullet types needed)
#include "physics_world.hpp"

#include "actionshift/core/rng.hpp"
#include "actionshift/sim/bench.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/kinematics.hpp"

#include <gtest/gtest.h>

namespace actionshift::sim::detail {
namespace {

struct Fixture {
  const RobotDescription& desc = panda_description();
  ArticulationLayout layout{desc};
  Eigen::Isometry3d base = Eigen::Translation3d(-0.615, 0, 0) * Eigen::Isometry3d::Identity();
  PhysicsWorld world{desc, layout, PhysicsConfig{}, base, {7, 8}};
};

TEST(PhysicsWorld, LayoutMergesFixedLinksIntoNineBodies) {
  Fixture f;
  ASSERT_EQ(f.layout.bodies.size(), 9u);
  EXPECT_EQ(f.layout.bodies[6].link_name, "panda_link7");
  EXPECT_EQ(f.layout.bodies[7].link_name, "panda_leftfinger");
  EXPECT_EQ(f.layout.mimic_of[8], 7);
  // link7 + link8 + hand (+ massless tcp) merged: 0.735522 + 0.73 kg
  EXPECT_NEAR(f.layout.bodies[6].mass, 1.465522, 1e-12);
}

TEST(PhysicsWorld, BulletKinematicsAgreesWithTheEigenChain) {
  Fixture f;
  const KinematicChain link7(f.desc, "panda_link7");
  Rng rng(5);
  for (int n = 0; n < 50; ++n) {
    Eigen::VectorXd q(9);
    for (int i = 0; i < 7; ++i) q(i) = rng.uniform(link7.lower()(i), link7.upper()(i));
    q(7) = q(8) = rng.uniform(0.0, 0.04);
    f.world.rebuild({}, q);
    const Eigen::Isometry3d bullet = f.world.body_urdf_pose(6);
    const Eigen::Isometry3d eigen = f.base * link7.fk(q.head<7>());
    EXPECT_LT((bullet.matrix() - eigen.matrix()).cwiseAbs().maxCoeff(), 1e-9) << "configuration " << n;
  }
}

TEST(PhysicsWorld, ArmHoldsItsPoseAgainstGravityAndFingersMoveTogether) {
  Fixture f;
  Eigen::VectorXd q(9);
  q << 0, 0.3927, 0, -1.9635, 0, 2.3562, 0.7854, 0.04, 0.04;
  f.world.rebuild({}, q);
  Eigen::VectorXd target = q;
  target(7) = target(8) = 0.01;
  f.world.set_targets(target);
  for (int i = 0; i < 20; ++i) f.world.step_control();  // 1 s
  const Eigen::VectorXd now = f.world.qpos();
  EXPECT_LT((now.head<7>() - q.head<7>()).cwiseAbs().maxCoeff(), 1e-6) << "the drives hold the pose";
  EXPECT_NEAR(now(7), 0.01, 1e-3);
  EXPECT_NEAR(now(7), now(8), 1e-4);
}

TEST(PhysicsWorld, GravityCompensationIsExactWithTheArmDrivesSwitchedOff) {
  const RobotDescription& desc = panda_description();
  const ArticulationLayout layout(desc);
  const Eigen::Isometry3d base = Eigen::Translation3d(-0.615, 0, 0) * Eigen::Isometry3d::Identity();
  PhysicsConfig limp;
  limp.arm_force_limit = 0.0;  // the motors cannot push: only gravity and its compensation act
  PhysicsWorld world(desc, layout, limp, base, {7, 8});
  Eigen::VectorXd q(9);
  q << 0.3, 0.2, -0.4, -1.5, 0.6, 1.9, 0.1, 0.04, 0.04;
  world.rebuild({}, q);
  world.set_targets(q);
  for (int i = 0; i < 20; ++i) world.step_control();  // 1 s
  EXPECT_LT((world.qpos().head<7>() - q.head<7>()).cwiseAbs().maxCoeff(), 1e-9);
  // control: the same limp arm without the compensation falls
  PhysicsConfig uncompensated = limp;
  uncompensated.gravity_compensation = false;
  PhysicsWorld falling(desc, layout, uncompensated, base, {7, 8});
  falling.rebuild({}, q);
  falling.set_targets(q);
  for (int i = 0; i < 20; ++i) falling.step_control();
  EXPECT_GT((falling.qpos().head<7>() - q.head<7>()).cwiseAbs().maxCoeff(), 0.01);
}

// the raw-Bullet limit steps the same world with the recorded controller inputs: the states must be
// the controlled run's bit for bit, and a perturbed input must show (the inputs are really applied)
void check_replay(const PhysicsConfig& cfg) {
  const RobotDescription& desc = panda_description();
  const ArticulationLayout layout(desc);
  const Eigen::Isometry3d base = Eigen::Translation3d(-0.615, 0, 0) * Eigen::Isometry3d::Identity();
  PhysicsWorld world(desc, layout, cfg, base, {7, 8});
  ObjectSpec cube;
  cube.boxes.push_back({Eigen::Vector3d::Constant(0.02), Eigen::Isometry3d::Identity()});
  cube.mass = 0.064;
  cube.position = Eigen::Vector3d(0.0, 0.0, 0.02);
  Eigen::VectorXd q(9);
  q << 0, 0.3927, 0, -1.9635, 0, 2.3562, 0.7854, 0.04, 0.04;
  BulletInputRecorder rec;
  set_thread_input_recorder(&rec);
  world.rebuild({cube}, q);
  ASSERT_EQ(rec.world, &world);
  Eigen::VectorXd target = q;
  for (int k = 0; k < 12; ++k) {
    target(1) += 0.02;  // reach forward and down, close the fingers: the drives and motors all work
    target(3) += 0.015;
    target(7) = target(8) = 0.04 - 0.003 * k;
    world.set_targets(target);
    world.step_control();
  }
  ASSERT_EQ(rec.inputs.size(), 12u * static_cast<std::size_t>(world.inputs_per_control_step()));
  const Eigen::VectorXd q_end = world.qpos(), v_end = world.qvel();
  const Eigen::Isometry3d cube_end = world.object_pose(0);
  EXPECT_GT((q_end - q).cwiseAbs().maxCoeff(), 0.05) << "the arm moved";

  rec.recording = false;
  world.rebuild({cube}, q);
  const int stride = world.inputs_per_control_step();
  for (int k = 0; k < 12; ++k) world.replay_control(rec.inputs.data() + k * stride);
  EXPECT_TRUE(world.qpos() == q_end);
  EXPECT_TRUE(world.qvel() == v_end);
  EXPECT_TRUE(world.object_pose(0).matrix() == cube_end.matrix());

  std::vector<double> perturbed = rec.inputs;
  const std::size_t arm_entry = cfg.arm_drive == ArmDrive::kImplicitPd ? 3 * 1 : 3 * 1 + 1;  // joint 2's torque or target
  perturbed[arm_entry] += 1e-3;
  world.rebuild({cube}, q);
  for (int k = 0; k < 12; ++k) world.replay_control(perturbed.data() + k * stride);
  EXPECT_FALSE(world.qpos() == q_end);
  set_thread_input_recorder(nullptr);
}

TEST(PhysicsWorld, ReplayWithRecordedInputsReproducesTheControlledRunBitForBit) {
  check_replay(PhysicsConfig{});  // maniskill: implicit PD torques on the arm
  PhysicsConfig servo;
  servo.arm_drive = ArmDrive::kVelocityServo;  // ideal: motors on every joint
  servo.arm_joint_limits = false;
  check_replay(servo);
}

TEST(PhysicsWorld, RawBulletLimitReplaysWholeEpisodesIdentically) {
  const RawBulletLimit r = measure_raw_bullet(TaskId::kPickCube, 60, 3);
  EXPECT_EQ(r.steps, 60);
  EXPECT_EQ(r.episodes, 2);  // pick_cube's horizon is 50
  EXPECT_TRUE(r.identical);
  EXPECT_GT(r.env_seconds, 0.0);
  EXPECT_GT(r.raw_seconds, 0.0);
  EXPECT_NEAR(r.ratio, r.raw_seconds / r.env_seconds, 1e-12);
  EXPECT_THROW(measure_raw_bullet(TaskId::kPickCube, 0), std::invalid_argument);
}

}  // namespace
}  // namespace actionshift::sim::detail
