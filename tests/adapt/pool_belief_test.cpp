#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/pool_belief.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "synthetic.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>

namespace actionshift::adapt {
namespace {

using actionshift::testing::intent;
using actionshift::testing::pick_like;
using actionshift::testing::run_synthetic;

// the reference pool with the truth moved to the end (a reference-implementation unit test, "truth last"; docs/reference.md, Pool belief)
std::vector<Contract> pool_with_truth_last(const Contract& truth) {
  std::vector<Contract> pool;
  for (const auto& c : reference::pool9())
    if (!(c == truth)) pool.push_back(c);
  pool.push_back(truth);
  return pool;
}

TEST(PoolBelief, StartsUniformWithIdentityAsMap) {
  PoolBelief b(reference::pool9(), pick_like());
  EXPECT_EQ(b.map_index(), 0);
  EXPECT_NEAR(b.probs().sum(), 1.0, 1e-12);
  EXPECT_NEAR(b.entropy(), std::log(9.0), 1e-12);
}

TEST(PoolBelief, IdentifiesTruthWithin40StepsAndReachesOracleParity) {
  for (const char* split : {"seen", "unseen_composition", "long_lag"})
    for (const auto& truth : reference::representative_contracts(split)) {
      ExactBeliefAdapter a(pool_with_truth_last(truth), pick_like());
      const auto run = run_synthetic(a, truth, pick_like(), 40, 7);
      ASSERT_GT(run.steps_to_identify, 0) << truth.sha256();
      EXPECT_LE(run.steps_to_identify, 40);
      if (truth.lag() == 0) {
        EXPECT_LT(run.final_intent_error, 1e-5) << truth.sha256();
      }
    }
}

TEST(PoolBelief, PoolWithoutTruthDoesNotReachParity) {
  const Contract truth = reference::representative_contracts("seen")[1];
  std::vector<Contract> pool;
  for (const auto& c : reference::pool9())
    if (!(c == truth)) pool.push_back(c);
  ExactBeliefAdapter a(pool, pick_like());
  const auto run = run_synthetic(a, truth, pick_like(), 40, 7);
  EXPECT_GT(run.final_intent_error, 0.1);
}

TEST(PoolBelief, ReplicasMatchTheWrapperDecoderThroughAbsoluteToolLagGripperAndResets) {
  // invariant from the reference implementation's tests (docs/reference.md, Pool belief): replicas are bit-faithful copies of the environment's decoder
  auto f = reference::representative_contracts("unseen_composition")[0].fields();
  f.lag = 2;
  const Contract truth = Contract::make(f);
  PoolBelief b({Contract::identity(), truth}, pick_like());
  Decoder env(truth);
  Rng rng(5);
  for (int t = 0; t < 60; ++t) {
    const bool reset = t == 23;
    const Mat3 R = actionshift::testing::random_rotation(rng);
    const Action raw = actionshift::testing::random_action(rng);
    const Action want = env.step(raw, R, reset);
    b.update(raw, pick_like().expected(want), R, reset);
    std::vector<Action> preds;
    EXPECT_EQ(b.replica(1).tracked_target(), env.tracked_target()) << t;
  }
}

TEST(PoolBelief, InvalidMaskDiscardsEvidenceAndReturnsToUniform) {
  const Contract truth = reference::oracle_contract();
  PoolBelief b(reference::pool9(), pick_like());
  Decoder env(truth);
  for (int k = 0; k < 10; ++k) {
    const Action raw = intent(k);
    b.update(raw, pick_like().expected(env.step(raw)), Mat3::Identity());
  }
  EXPECT_EQ(b.map_index(), 1);
  b.update(intent(11), Pose6::Constant(5.0), Mat3::Identity(), false, /*invalid=*/true);
  EXPECT_NEAR(b.entropy(), std::log(9.0), 1e-12);
}

TEST(PoolBelief, StaysNormalisedAndFiniteUnderSurprisingEvidence) {
  PoolBelief b(reference::pool9(), pick_like());
  for (int k = 0; k < 100; ++k) b.update(intent(k), Pose6::Constant(100.0), Mat3::Identity());
  EXPECT_NEAR(b.probs().sum(), 1.0, 1e-9);
  EXPECT_TRUE(b.log_probs().allFinite() || b.log_probs().maxCoeff() == 0.0);
}

TEST(PoolBelief, MapEncodeRoundTripsAbsoluteTargets) {
  // invariant from the reference implementation's tests (docs/reference.md, Pool belief): once the MAP is the truth, encoding through it is exact
  const Contract truth = reference::representative_contracts("unseen_composition")[1];  // absolute
  ExactBeliefAdapter a(pool_with_truth_last(truth), pick_like());
  const auto run = run_synthetic(a, truth, pick_like(), 30, 3, /*noise_scale=*/0.0);
  EXPECT_GT(run.steps_to_identify, 0);
  EXPECT_LT(run.final_intent_error, 1e-12);
}

TEST(OracleAndNoAdapt, OracleInvertsAbsoluteTargetsAndNoAdaptPassesThrough) {
  const Contract truth = reference::representative_contracts("unseen_composition")[0];
  OracleAdapter o(truth);
  Decoder env(truth);
  o.begin_episode(0);
  Rng rng(9);
  for (int k = 0; k < 50; ++k) {
    const Mat3 R = actionshift::testing::random_rotation(rng);
    const Action raw = o.encode(intent(k), R);
    const Action exec = env.step(raw, R);
    o.observe(raw, Pose6::Zero(), R);
    EXPECT_LT((exec - intent(k)).cwiseAbs().maxCoeff(), 1e-12);
  }
  NoAdaptAdapter n;
  EXPECT_EQ(n.encode(intent(3), Mat3::Identity()), intent(3));
}

// the diagnostic oracle: `delay` steps of no adaptation (or of holding still through the truth), then the
// oracle exactly, with the target it tracked through the delay (an absolute-target contract drifts while
// the intents go unadapted, so an oracle that forgot those steps would miss by the drift)
TEST(DelayedOracle, SendsTheIntentUnchangedForDelayStepsThenInvertsExactly) {
  const Contract truth = reference::representative_contracts("unseen_composition")[0];
  ASSERT_EQ(truth.lag(), 0);
  for (const int delay : {0, 1, 6}) {
    DelayedOracleAdapter o(truth, delay, DelayedOracleAdapter::Before::kNoAdapt);
    Decoder env(truth);
    for (int episode = 0; episode < 2; ++episode) {  // begin_episode clears the count and the replica
      o.begin_episode(0);
      env.reset_all();
      Rng rng(11);
      for (int k = 0; k < 20; ++k) {
        const Mat3 R = actionshift::testing::random_rotation(rng);
        const Action raw = o.encode(intent(k), R);
        const Action exec = env.step(raw, R);
        o.observe(raw, Pose6::Zero(), R);
        if (k < delay) {
          EXPECT_EQ(raw, intent(k)) << "delay " << delay << " step " << k;
          EXPECT_GT((exec - intent(k)).cwiseAbs().maxCoeff(), 1e-3) << "the contract must mis-map the intent";
        } else {
          EXPECT_LT((exec - intent(k)).cwiseAbs().maxCoeff(), 1e-12) << "delay " << delay << " step " << k;
        }
      }
    }
  }
}

TEST(DelayedOracle, HoldSendsAZeroPoseWithTheIntentsGripperThroughTheTruth) {
  const Contract truth = reference::representative_contracts("unseen_composition")[0];
  DelayedOracleAdapter o(truth, 3, DelayedOracleAdapter::Before::kHold);
  Decoder env(truth);
  o.begin_episode(0);
  Rng rng(5);
  for (int k = 0; k < 8; ++k) {
    const Mat3 R = actionshift::testing::random_rotation(rng);
    const Action raw = o.encode(intent(k), R);
    const Action exec = env.step(raw, R);
    o.observe(raw, Pose6::Zero(), R);
    Action want = intent(k);
    if (k < 3) want.head<kPoseDim>().setZero();
    EXPECT_LT((exec - want).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
    EXPECT_FALSE(o.last_step().probe);
  }
}

}  // namespace
}  // namespace actionshift::adapt
