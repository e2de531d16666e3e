// forward kinematics of the panda urdf: rest pose, agreement with franka's modified dh, jacobian
#include "actionshift/sim/kinematics.hpp"

#include "actionshift/core/rng.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace actionshift::sim {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::Matrix<double, 7, 1> rest() {
  Eigen::Matrix<double, 7, 1> q;
  q << 0, kPi / 8, 0, -5 * kPi / 8, 0, 3 * kPi / 4, kPi / 4;
  return q;
}

TEST(Kinematics, TcpAtRestIsAboveTheWorldOriginPointingDown) {
  const KinematicChain tcp(panda_description(), "panda_hand_tcp");
  ASSERT_EQ(tcp.dof(), 7);
  const Eigen::Isometry3d t = tcp.fk(rest());
  const Eigen::Vector3d world = t.translation() + Eigen::Vector3d(-0.615, 0, 0);
  EXPECT_NEAR(world.x(), 0.0, 5e-5);
  EXPECT_NEAR(world.y(), 0.0, 1e-12);
  EXPECT_NEAR(world.z(), 0.1698, 5e-5);
  // hand z down, hand x along world +x, hand y along world -y (the rest keyframe, docs/sim.md §1)
  EXPECT_TRUE(t.linear().col(2).isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_TRUE(t.linear().col(0).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  EXPECT_TRUE(t.linear().col(1).isApprox(Eigen::Vector3d(0, -1, 0), 1e-12));
  // joint 7 = -pi/4 (wristcam rest): same position, fingers along world x
  Eigen::Matrix<double, 7, 1> q = rest();
  q(6) = -kPi / 4;
  const Eigen::Isometry3d w = tcp.fk(q);
  EXPECT_TRUE(w.translation().isApprox(t.translation(), 1e-12));
  EXPECT_NEAR(std::abs(w.linear().col(1).x()), 1.0, 1e-12);
}

TEST(Kinematics, ZeroPoseFlangeMatchesFranka) {
  const KinematicChain flange(panda_description(), "panda_link8");
  const Eigen::Isometry3d t = flange.fk(Eigen::Matrix<double, 7, 1>::Zero());
  EXPECT_TRUE(t.translation().isApprox(Eigen::Vector3d(0.088, 0, 0.926), 1e-12));
}

TEST(Kinematics, AgreesWithFrankaModifiedDhOn1000RandomConfigurations) {
  const KinematicChain flange(panda_description(), "panda_link8");
  const KinematicChain tcp(panda_description(), "panda_hand_tcp");
  Rng rng(42);
  Eigen::Isometry3d hand_tcp = Eigen::Isometry3d::Identity();
  hand_tcp.rotate(Eigen::AngleAxisd(-kPi / 4, Eigen::Vector3d::UnitZ()));
  hand_tcp.translate(Eigen::Vector3d(0, 0, 0.1034));
  double worst = 0;
  for (int n = 0; n < 1000; ++n) {
    Eigen::Matrix<double, 7, 1> q;
    for (int i = 0; i < 7; ++i) q(i) = rng.uniform(flange.lower()(i), flange.upper()(i));
    const Eigen::Isometry3d dh = franka_dh_flange(q);
    worst = std::max(worst, (flange.fk(q).matrix() - dh.matrix()).cwiseAbs().maxCoeff());
    worst = std::max(worst, (tcp.fk(q).matrix() - (dh * hand_tcp).matrix()).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(Kinematics, JacobianMatchesFiniteDifferences) {
  const KinematicChain tcp(panda_description(), "panda_hand_tcp");
  Rng rng(7);
  for (int n = 0; n < 20; ++n) {
    Eigen::Matrix<double, 7, 1> q;
    for (int i = 0; i < 7; ++i) q(i) = rng.uniform(tcp.lower()(i), tcp.upper()(i));
    Eigen::Isometry3d t;
    ChainJacobian j;
    tcp.fk_jacobian(q, t, j);
    EXPECT_TRUE(t.isApprox(tcp.fk(q), 1e-14));
    for (int i = 0; i < 7; ++i) {
      const double h = 1e-6;
      Eigen::Matrix<double, 7, 1> qp = q, qm = q;
      qp(i) += h;
      qm(i) -= h;
      const Eigen::Isometry3d tp = tcp.fk(qp), tm = tcp.fk(qm);
      const Eigen::Vector3d v = (tp.translation() - tm.translation()) / (2 * h);
      const Eigen::Vector3d w = so3_log(tp.linear() * tm.linear().transpose()) / (2 * h);
      EXPECT_LT((v - j.block<3, 1>(0, i)).norm(), 1e-7);
      EXPECT_LT((w - j.block<3, 1>(3, i)).norm(), 1e-7);
    }
  }
}

TEST(Kinematics, So3AndQuaternionHelpersRoundTrip) {
  const Eigen::Vector3d rv(0.3, -0.2, 0.9);
  EXPECT_TRUE(so3_log(so3_exp(rv)).isApprox(rv, 1e-12));
  const Eigen::Matrix3d r = so3_exp(rv);
  const Eigen::Vector4d q = matrix_to_quat_wxyz(r);
  EXPECT_GE(q(0), 0.0);
  EXPECT_TRUE(quat_wxyz_to_rotation(q).isApprox(r, 1e-12));
}

}  // namespace
}  // namespace actionshift::sim
