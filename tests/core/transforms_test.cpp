#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/core/transforms.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>

namespace actionshift {
namespace {

using testing::action;

void expect_near(const Action& got, const Action& want, double tol) {
  for (int i = 0; i < kActionDim; ++i) EXPECT_NEAR(got[i], want[i], tol) << "channel " << i;
}

TEST(DecodePose, PermutationThenSignThenScaleIndexedByOutput) {
  // the reference implementation's decode example (docs/reference.md, Contracts) scaled up to 6 channels: perm (1,0,…), sign (1,−1,…), scale (0.5, 2.0, …)
  ContractFields f;
  f.permutation = {1, 0, 2, 3, 4, 5};
  f.sign = {1, -1, 1, 1, 1, 1};
  f.scale = {0.5, 2.0, 1.0, 1.0, 1.0, 1.0};
  const Contract c = Contract::make(f);
  Pose6 raw;
  raw << 2, 3, 0, 0, 0, 0;
  const Pose6 d = decode_pose(c, raw);
  EXPECT_DOUBLE_EQ(d[0], 1.5);
  EXPECT_DOUBLE_EQ(d[1], -4.0);
  EXPECT_EQ(encode_pose(c, d), raw);
}

TEST(Decode, GoldenOracleContract) {
  // reference A.2: oracle_contract, R = I, T = 0
  const Action raw = action({0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7});
  const Action got = decode(reference::oracle_contract(), raw, Mat3::Identity(), Pose6::Zero());
  expect_near(got, action({0.1, 0.2, -0.45, 0.375, 0.75, -0.24, -0.7}), 1e-12);
}

TEST(Decode, GoldenAbsoluteToolContract) {
  // reference A.2: unseen_composition[0] (absolute, tool), R = [[0,0,1],[1,0,0],[0,1,0]]
  const Contract c = reference::representative_contracts("unseen_composition")[0];
  Mat3 R;
  R << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  Pose6 T;
  T << 0.01, 0.02, 0.03, 0.04, 0.05, 0.06;
  Pose6 next;
  const Action got = decode(c, action({0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7}), R, T, &next);
  expect_near(got, action({-0.46, 0.08, 0.17, -0.28, 0.325, 0.69, -0.7}), 1e-12);
  Pose6 want_next;
  want_next << -0.45, 0.1, 0.2, -0.24, 0.375, 0.75;
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(next[i], want_next[i], 1e-12);
  const Action raw = encode(c, action({0.05, -0.02, 0.01, 0.0, 0.03, -0.04, -1.0}), R, T);
  expect_near(raw, action({0.02, -0.0, -0.04, 0.0666666666667, 0.1066666666667, -0.016, 1.0}), 1e-12);
}

TEST(Decode, ToolFrameRotatesTranslationAndRotationAndGripperIsOnlyNegated) {
  // invariant from the reference implementation's tests (docs/reference.md, Contracts): tool frame with a 90° z rotation maps x-translation to y
  auto f = Contract::identity().fields();
  f.frame = "tool";
  f.gripper_inverted = true;
  const Contract c = Contract::make(f);
  const Mat3 Rz = quat_wxyz_to_matrix(Eigen::Vector4d(std::sqrt(0.5), 0, 0, std::sqrt(0.5)));
  const Action got = decode(c, action({1, 0, 0, 1, 0, 0, 0.3}), Rz, Pose6::Zero());
  expect_near(got, action({0, 1, 0, 0, 1, 0, -0.3}), 1e-12);
}

TEST(Decode, AbsoluteTargetIsOffsetFromTrackedTarget) {
  auto f = Contract::identity().fields();
  f.target = "absolute";
  const Contract c = Contract::make(f);
  Pose6 T = Pose6::Zero();
  Pose6 next;
  Action a = decode(c, action({0.3, 0, 0, 0, 0, 0, 0}), Mat3::Identity(), T, &next);
  EXPECT_DOUBLE_EQ(a[0], 0.3);
  a = decode(c, action({0.3, 0, 0, 0, 0, 0, 0}), Mat3::Identity(), next, &next);
  EXPECT_DOUBLE_EQ(a[0], 0.0);  // holding the same absolute command means no motion
  EXPECT_DOUBLE_EQ(next[0], 0.3);
}

TEST(QuatToMatrix, KnownValues) {
  EXPECT_TRUE(quat_wxyz_to_matrix(Eigen::Vector4d(1, 0, 0, 0)).isApprox(Mat3::Identity()));
  Mat3 want;
  want << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  EXPECT_TRUE(quat_wxyz_to_matrix(Eigen::Vector4d(0.5, 0.5, 0.5, 0.5)).isApprox(want, 1e-15));
  Mat3 rz;
  rz << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_TRUE(quat_wxyz_to_matrix(Eigen::Vector4d(std::sqrt(0.5), 0, 0, std::sqrt(0.5))).isApprox(rz, 1e-15));
  EXPECT_TRUE(is_rotation(quat_wxyz_to_matrix(Eigen::Vector4d(3, -1, 2, 0.5))));
}

TEST(IsRotation, RejectsNonRotations) {
  std::string why;
  EXPECT_FALSE(is_rotation(2.0 * Mat3::Identity(), &why));
  EXPECT_EQ(why, "rotation matrix is not orthonormal");
  EXPECT_FALSE(is_rotation(-Mat3::Identity(), &why));
  EXPECT_EQ(why, "rotation matrix has non-positive determinant");
  Mat3 n = Mat3::Identity();
  n(0, 0) = std::nan("");
  EXPECT_FALSE(is_rotation(n, &why));
}

TEST(RoundTrip, DecodeOfEncodeIsIdentityOver10000RandomCases) {
  Rng rng(testing::test_seed());
  double worst = 0.0;
  for (int k = 0; k < 10000; ++k) {
    const Contract c = testing::random_contract(rng);
    const Mat3 R = testing::random_rotation(rng);
    Pose6 T;
    for (int i = 0; i < 6; ++i) T[i] = rng.uniform(-2, 2);
    const Action x = testing::random_action(rng);
    Pose6 next;
    const Action back = decode(c, encode(c, x, R, T), R, T, &next);
    worst = std::max(worst, (back - x).cwiseAbs().maxCoeff());
    EXPECT_LT((next - (T + x.head<6>())).cwiseAbs().maxCoeff(), 1e-12);
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(DecodeJacobian, MatchesFiniteDifferences) {
  Rng rng(testing::test_seed() + 1);
  for (int k = 0; k < 200; ++k) {
    const Contract c = testing::random_contract(rng);
    const Mat3 R = testing::random_rotation(rng);
    Pose6 T;
    for (int i = 0; i < 6; ++i) T[i] = rng.uniform(-1, 1);
    const Action raw = testing::random_action(rng);
    const ActionJacobian J = decode_jacobian(c, R);
    const double h = 1e-6;
    for (int j = 0; j < kActionDim; ++j) {
      Action p = raw, m = raw;
      p[j] += h;
      m[j] -= h;
      const Action fd = (decode(c, p, R, T) - decode(c, m, R, T)) / (2 * h);
      EXPECT_LT((fd - J.col(j)).cwiseAbs().maxCoeff(), 1e-8) << "column " << j;
    }
  }
}

}  // namespace
}  // namespace actionshift
