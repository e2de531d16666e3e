// the hand-built bullet articulation: its kinematics agree with the eigen chain, gravity is
// compensated, the mimic fingers move together (private header, no bullet types needed)
#include "physics_world.hpp"

#include "actionshift/core/rng.hpp"
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

}  // namespace
}  // namespace actionshift::sim::detail
