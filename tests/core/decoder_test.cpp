#include "actionshift/core/decoder.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "test_util.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <deque>

namespace actionshift {
namespace {

using testing::action;

Contract with_lag(const Contract& c, int lag, const char* target = nullptr) {
  auto f = c.fields();
  f.lag = lag;
  if (target) f.target = target;
  return Contract::make(f);
}

TEST(Decoder, LagEmitsZerosThenDelayedActions) {
  Decoder d(with_lag(Contract::identity(), 2));
  const Action a1 = action({1, 0, 0, 0, 0, 0, 10}), a2 = action({2, 0, 0, 0, 0, 0, 20}),
               a3 = action({3, 0, 0, 0, 0, 0, 30});
  EXPECT_EQ(d.step(a1), Action::Zero());
  EXPECT_EQ(d.step(a2), Action::Zero());
  EXPECT_EQ(d.step(a3), a1);  // the gripper is delayed too
  EXPECT_EQ(d.step(a3), a2);
}

TEST(Decoder, GoldenAbsoluteWithLag2) {
  // reference A.2: identity with absolute target and lag 2; raws x0 = 0.1·(k+1), gripper 0.5
  Decoder d(with_lag(Contract::identity(), 2, "absolute"));
  for (int k = 0; k < 5; ++k) {
    const Action out = d.step(action({0.1 * (k + 1), 0, 0, 0, 0, 0, 0.5}));
    if (k < 2) {
      EXPECT_EQ(out, Action::Zero()) << k;
    } else {
      EXPECT_NEAR(out[0], 0.1, 1e-12) << k;
      EXPECT_DOUBLE_EQ(out[6], 0.5);
      EXPECT_EQ(out.segment<5>(1), (Eigen::Matrix<double, 5, 1>::Zero()));
    }
  }
}

TEST(Decoder, ReferenceLag1Vector) {
  // the reference implementation's decoder example (docs/reference.md, Contracts): perm (1,0)/sign (1,−1)/scale (0.5,2.0)/lag 1, raws [2,3] then [4,5]
  ContractFields f;
  f.permutation = {1, 0, 2, 3, 4, 5};
  f.sign = {1, -1, 1, 1, 1, 1};
  f.scale = {0.5, 2.0, 1, 1, 1, 1};
  f.lag = 1;
  Decoder d(Contract::make(f));
  EXPECT_EQ(d.step(action({2, 3, 0, 0, 0, 0, 0})), Action::Zero());
  const Action out = d.step(action({4, 5, 0, 0, 0, 0, 0}));
  EXPECT_DOUBLE_EQ(out[0], 1.5);
  EXPECT_DOUBLE_EQ(out[1], -4.0);
}

TEST(Decoder, ResetMaskClearsOnlySelectedEnv) {
  // the reference implementation's decoder example (docs/reference.md, Contracts): absolute + lag 1, batch 2, reset env 0 on step 2 → env 0 outputs zeros,
  // env 1 outputs its first action's pose
  Decoder d(with_lag(Contract::identity(), 1, "absolute"), 2);
  Decoder::Batch raw(7, 2), out(7, 2);
  raw.col(0) = action({0.1, 0.2, 0, 0, 0, 0, 1});
  raw.col(1) = action({0.3, 0.4, 0, 0, 0, 0, -1});
  d.step(raw, {}, {}, out);
  EXPECT_EQ(out, Decoder::Batch::Zero(7, 2));
  const std::array<bool, 2> mask{true, false};
  d.step(raw, {}, mask, out);
  EXPECT_EQ(out.col(0), Action::Zero());
  EXPECT_EQ(out.col(1), raw.col(1));
  // env 0 restarted: its tracked target is the raw pose again, env 1 holds its target
  EXPECT_NEAR(d.tracked_target(0)[0], 0.1, 1e-15);
  EXPECT_NEAR(d.tracked_target(1)[0], 0.3, 1e-15);
  d.step(raw, {}, {}, out);
  EXPECT_EQ(out.col(0), raw.col(0));  // first action of env 0's new episode
  EXPECT_EQ(out.col(1).head<6>(), Pose6::Zero());  // env 1 held the same absolute command
}

TEST(Decoder, SingleStepResetStartsANewEpisode) {
  Decoder d(with_lag(Contract::identity(), 1, "absolute"));
  d.step(action({0.5, 0, 0, 0, 0, 0, 0}));
  d.step(action({0.7, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(d.step(action({0.2, 0, 0, 0, 0, 0, 0}), Mat3::Identity(), /*reset=*/true), Action::Zero());
  EXPECT_NEAR(d.step(action({0.2, 0, 0, 0, 0, 0, 0}))[0], 0.2, 1e-15);
}

TEST(Decoder, BatchedEqualsPerEnvReplicasUnderRandomContractsRotationsAndResets) {
  Rng rng(testing::test_seed());
  for (int trial = 0; trial < 50; ++trial) {
    const Contract c = testing::random_contract(rng);
    const int n = 1 + static_cast<int>(rng.uniform_int(5));
    Decoder batched(c, n);
    std::vector<Decoder> singles(static_cast<std::size_t>(n), Decoder(c));
    Decoder::Batch raw(7, n), out(7, n);
    std::vector<Mat3> R(static_cast<std::size_t>(n));
    std::unique_ptr<bool[]> mask(new bool[static_cast<std::size_t>(n)]);
    for (int t = 0; t < 30; ++t) {
      for (int e = 0; e < n; ++e) {
        raw.col(e) = testing::random_action(rng);
        R[static_cast<std::size_t>(e)] = testing::random_rotation(rng);
        mask[static_cast<std::size_t>(e)] = rng.uniform() < 0.1;
      }
      batched.step(raw, R, std::span<const bool>(mask.get(), static_cast<std::size_t>(n)), out);
      for (int e = 0; e < n; ++e) {
        const Action want = singles[static_cast<std::size_t>(e)].step(raw.col(e), R[static_cast<std::size_t>(e)],
                                                                      mask[static_cast<std::size_t>(e)]);
        ASSERT_EQ(out.col(e), want) << "trial " << trial << " step " << t << " env " << e;
      }
    }
  }
}

TEST(Decoder, OracleEncodeThroughDecoderReproducesCanonicalAfterLag) {
  Rng rng(testing::test_seed() + 7);
  for (int trial = 0; trial < 100; ++trial) {
    const Contract c = testing::random_contract(rng);
    Decoder d(c);
    std::deque<Action> sent;
    for (int t = 0; t < 40; ++t) {
      const Mat3 R = testing::random_rotation(rng);
      const Action x = testing::random_action(rng);
      const Action out = d.step(encode(c, x, R, d.tracked_target()), R);
      sent.push_back(x);
      if (t < c.lag()) {
        EXPECT_EQ(out, Action::Zero());
      } else {
        EXPECT_LT((out - sent.front()).cwiseAbs().maxCoeff(), 1e-12);
        sent.pop_front();
      }
    }
  }
}

TEST(Decoder, RejectsBadShapes) {
  using ::testing::HasSubstr;
  using ::testing::ThrowsMessage;
  EXPECT_THAT([] { Decoder d(Contract::identity(), 0); }, ThrowsMessage<std::invalid_argument>(HasSubstr("at least one")));
  Decoder d(Contract::identity(), 2);
  Decoder::Batch raw(7, 3), out(7, 3);
  raw.setZero();
  EXPECT_THAT([&] { d.step(raw, {}, {}, out); }, ThrowsMessage<std::invalid_argument>(HasSubstr("batch size is 2, got 3")));
  EXPECT_THAT([&] { d.step(Action::Zero()); }, ThrowsMessage<std::invalid_argument>(HasSubstr("one environment")));
  EXPECT_THROW(d.reset(2), std::invalid_argument);
}

}  // namespace
TEST(Decoder, RefusesASizeWhoseStateWouldTakeAGigabyte) {
  // num_envs x (lag + 1) slots of 7 doubles: 10**5 environments at lag 1024 would touch 5.6 GB
  EXPECT_THROW(Decoder(Contract::identity(), (1 << 24) + 1), std::invalid_argument);
  ContractFields f = Contract::identity().fields();
  f.lag = 1024;
  EXPECT_THROW(Decoder(Contract::make(f), 100000), std::invalid_argument);
  EXPECT_NO_THROW(Decoder(Contract::make(f), 1000));
}

}  // namespace actionshift
