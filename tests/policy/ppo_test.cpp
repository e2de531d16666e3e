// PPO: GAE against a hand computation, the update moves the policy and the critic the right way,
// a tiny end-to-end run is deterministic whatever the thread count and loads as a backbone
#include "actionshift/policy/ppo.hpp"

#include "actionshift/core/hash.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

using namespace actionshift;

namespace {

TEST(PpoGae, MatchesAHandComputation) {
  // 2 envs x 3 steps, time-major (k = t * 2 + e): env 0 ends by the time limit at t = 1 (k = 2, final
  // value 0.5) and starts a new episode at t = 2; env 1 ends by success at t = 0 (k = 1, no bootstrap)
  const Eigen::VectorXf r = (Eigen::VectorXf(6) << 1, 0, 0, 1, 2, 0).finished();
  const Eigen::VectorXf v = (Eigen::VectorXf(6) << 0.5f, 0.2f, 0.1f, 0.3f, 0.4f, 0.6f).finished();
  const Eigen::VectorXf fv = (Eigen::VectorXf(6) << 0, 0, 0.5f, 0, 0, 0).finished();
  const std::vector<std::uint8_t> ended = {0, 1, 1, 0, 0, 0};
  const Eigen::VectorXf next = (Eigen::VectorXf(2) << 0.7f, 0.9f).finished();
  const double g = 0.8, l = 0.9;
  const auto a = policy::gae(r, v, fv, ended, next, 2, g, l);
  const double e0t2 = 2 + g * 0.7 - 0.4;             // k=4, last step, bootstrap next_value(0)
  const double e0t1 = 0 + g * 0.5 - 0.1;             // k=2, ended (time limit)
  const double e0t0 = 1 + g * 0.1 - 0.5 + g * l * e0t1;  // k=0
  const double e1t2 = 0 + g * 0.9 - 0.6;             // k=5
  const double e1t1 = 1 + g * 0.6 - 0.3 + g * l * e1t2;  // k=3
  const double e1t0 = 0 + 0 - 0.2;                   // k=1, ended by success: no bootstrap
  EXPECT_NEAR(a(4), e0t2, 1e-5);
  EXPECT_NEAR(a(2), e0t1, 1e-5);
  EXPECT_NEAR(a(0), e0t0, 1e-5);
  EXPECT_NEAR(a(5), e1t2, 1e-5);
  EXPECT_NEAR(a(3), e1t1, 1e-5);
  EXPECT_NEAR(a(1), e1t0, 1e-5);
  EXPECT_THROW(policy::gae(r, v, fv, ended, next, 4, g, l), std::invalid_argument);
}

TEST(PpoUpdate, MovesTheMeanTowardsAdvantageousActionsAndTheValueTowardsTheReturns) {
  policy::PpoOptions o;
  o.hidden = {16, 16};
  o.num_minibatches = 2;
  o.update_epochs = 4;
  o.target_kl = 0;  // no early stop
  policy::PpoLearner learner(o, 5);
  const int n = 64;
  policy::PpoBatch b;
  b.obs = Eigen::MatrixXf::Constant(5, n, 0.3f);
  b.actions.resize(7, n);
  b.advantages.resize(n);
  for (int k = 0; k < n; ++k) {
    const float s = k % 2 == 0 ? 1.0f : -1.0f;  // +0.5 on channel 0 is good, -0.5 is bad
    b.actions.col(k) = Eigen::VectorXf::Zero(7);
    b.actions(0, k) = 0.5f * s;
    b.advantages(k) = s;
  }
  const Eigen::MatrixXf mean0 = learner.mean(b.obs);
  b.log_probs = learner.log_prob(mean0, b.actions);
  b.returns = Eigen::VectorXf::Constant(n, 1.0f);
  const float v0 = learner.value(b.obs.leftCols(1))(0);
  const auto stats = learner.update(b, 7, 2);
  EXPECT_EQ(stats.epochs, 4);
  const Eigen::MatrixXf mean1 = learner.mean(b.obs);
  EXPECT_GT(mean1(0, 0), mean0(0, 0) + 1e-3f);             // towards +0.5
  EXPECT_NEAR(mean1(1, 0), mean0(1, 0), 0.05f);            // untouched channel barely moves
  const float v1 = learner.value(b.obs.leftCols(1))(0);
  EXPECT_LT(std::abs(v1 - 1.0f), std::abs(v0 - 1.0f));     // critic towards the returns
  EXPECT_GT(stats.clip_fraction, -1e-9);
}

policy::PpoOptions tiny(unsigned threads) {
  policy::PpoOptions o;
  o.task = sim::TaskId::kPushCube;
  o.hidden = {16, 16};
  o.num_envs = 4;
  o.num_steps = 8;
  o.total_steps = 64;  // 2 iterations
  o.num_minibatches = 2;
  o.eval_every = 1;
  o.eval_episodes = 2;
  o.threads = threads;
  return o;
}

TEST(PpoTrain, DeterministicWhateverTheThreadsAndLoadsAsABackbone) {
  std::vector<policy::PpoIteration> its;
  int checkpoints = 0;
  const auto a = policy::train_ppo(tiny(1), {{"seed", 20260718}}, [&its](const policy::PpoIteration& i) { its.push_back(i); },
                                   [&checkpoints](const policy::MlpWeights&) { ++checkpoints; });
  const auto b = policy::train_ppo(tiny(2), {{"seed", 20260718}});
  ASSERT_EQ(its.size(), 2u);
  EXPECT_EQ(checkpoints, 2);
  EXPECT_EQ(its[1].env_steps, 64);
  EXPECT_GE(its[1].eval_success, 0.0);
  EXPECT_GT(its[0].mean_std, 0.5);
  const std::string bytes = policy::serialize_mlp(a.actor);
  EXPECT_EQ(bytes, policy::serialize_mlp(b.actor));
  auto o = tiny(2);
  o.seed = 99;
  EXPECT_NE(policy::serialize_mlp(policy::train_ppo(o, {}).actor), bytes);
  // the actor is an ordinary MLP backbone: parses, right shape, provenance recorded
  const auto w = policy::parse_mlp(bytes, "ppo.asmlp");
  EXPECT_EQ(w.layers, (std::vector<int>{35, 16, 16, 7}));
  EXPECT_EQ(w.training.at("env_steps"), 64);
  policy::MlpPolicy pol(std::make_shared<const policy::MlpWeights>(w), sha256_hex(bytes), "ppo");
  EXPECT_EQ(pol.name(), "ppo");
  EXPECT_EQ(pol.clone()->name(), "ppo");
}

// The tiny runs' weight files, byte for byte (SHA-256), for the plain and the delay-aware rollout: a change
// to the rollout loop (its environments, seeds, reset rule or order of work) that is meant to keep every
// committed backbone reproducible must keep these. Regenerate only for an intended change of training.
//
// The bytes are not the same on every machine of this workplace: the hashes below were recorded on the
// machine of 2026-11-27, and the same code at the same commit gives other hashes on the machine of
// 2026-11-28 (Intel Xeon, 48 KiB L1d, AVX-512), stable from run to run. The cause is not found: not Eigen's
// L1/L2 blocking sizes (16 KiB to 64 KiB tried), not glibc's FMA variants of libm (GLIBC_TUNABLES), not the
// CPU count. So each known machine's pair is accepted: a change of training still gives a third hash on
// either, and fails here. docs/backbones.md ("Re-training byte for byte") says what this means for the
// committed PPO files.
TEST(PpoTrain, TinyRunsKeepTheirBytes) {
  const std::string plain = sha256_hex(policy::serialize_mlp(policy::train_ppo(tiny(2), {{"seed", 20260718}}).actor));
  auto o = tiny(2);
  o.delay_aware = true;
  const std::string delay_aware = sha256_hex(policy::serialize_mlp(policy::train_ppo(o, {}).actor));
  const std::vector<std::pair<std::string, std::string>> known = {
      {"11236afa054278a0b4612ed34091a0ad58d95fa7e32ca906c2708cbe9a54e771", "7128055463bd08a530777d5b19d8abae4949986c6bef8fc11ba724c25d80c46e"},
      {"3e1ea8ceb1159cfa072139115fd09193dc12b79823f51ab1e27644ef45af97e5", "e72db34147b147364a0f8f7c3f2726feafff037445d80753d1eefcaa0e1b3daa"}};
  EXPECT_TRUE(std::find(known.begin(), known.end(), std::make_pair(plain, delay_aware)) != known.end())
      << "plain " << plain << ", delay-aware " << delay_aware << ": neither known machine's pair";
}

TEST(PpoTrain, DelayAwareSeesTheExecutedActionHistoryAndIsDeterministic) {
  auto o = tiny(1);
  o.delay_aware = true;
  std::vector<policy::MlpWeights> ck;
  const auto a = policy::train_ppo(o, {}, {}, [&ck](const policy::MlpWeights& w) { ck.push_back(w); });
  o.threads = 2;
  EXPECT_EQ(policy::serialize_mlp(policy::train_ppo(o, {}).actor), policy::serialize_mlp(a.actor));
  EXPECT_EQ(a.actor.history, policy::kHistoryLength);
  EXPECT_EQ(a.actor.layers, (std::vector<int>{35 + 7 * policy::kHistoryLength, 16, 16, 7}));
  // the history columns of the first layer are trained (a zero input would leave them untouched:
  // Adam moves nothing without a gradient), and so are the observation columns
  ASSERT_EQ(ck.size(), 2u);
  const auto& w0 = ck[0].w.front();
  const auto& w1 = ck[1].w.front();
  EXPECT_GT((w1.rightCols(7 * policy::kHistoryLength) - w0.rightCols(7 * policy::kHistoryLength)).norm(), 0.0f);
  EXPECT_GT((w1.leftCols(35) - w0.leftCols(35)).norm(), 0.0f);
  // loads as the delay-aware backbone; the plain `ppo` name is refused for a history network
  const auto w = policy::parse_mlp(policy::serialize_mlp(a.actor), "ppo-delay-aware.asmlp");
  EXPECT_EQ(w.history, policy::kHistoryLength);
}

TEST(PpoTrain, AnnealedLearningRateStartsAtTheSetRateAndThenDeparts) {
  auto o = tiny(1);
  std::vector<policy::MlpWeights> plain, annealed;
  policy::train_ppo(o, {}, {}, [&plain](const policy::MlpWeights& w) { plain.push_back(w); });
  o.anneal_lr = true;
  policy::train_ppo(o, {}, {}, [&annealed](const policy::MlpWeights& w) { annealed.push_back(w); });
  ASSERT_EQ(plain.size(), 2u);
  ASSERT_EQ(annealed.size(), 2u);
  // iteration 1 updates at lr * (1 - 0/2) = lr: the same weights; iteration 2 at lr / 2: different
  EXPECT_EQ(plain[0].w.front(), annealed[0].w.front());
  EXPECT_NE(plain[1].w.front(), annealed[1].w.front());
}

TEST(PpoTrain, StopAfterReproducesAnAnnealedRunsCheckpoint) {
  auto o = tiny(1);
  o.anneal_lr = true;
  o.total_steps = 128;  // 4 iterations, annealed over 4
  std::vector<policy::MlpWeights> ck;
  policy::train_ppo(o, {}, {}, [&ck](const policy::MlpWeights& w) { ck.push_back(w); });
  ASSERT_EQ(ck.size(), 4u);
  o.stop_steps = 64;  // stop after iteration 2, the schedule still over 4
  const auto stopped = policy::train_ppo(o, {});
  EXPECT_EQ(stopped.iterations.size(), 2u);
  EXPECT_EQ(stopped.actor.training.at("env_steps"), 64);
  EXPECT_EQ(stopped.actor.training.at("iterations"), 2);
  for (std::size_t i = 0; i < ck[1].w.size(); ++i) EXPECT_EQ(stopped.actor.w[i], ck[1].w[i]) << i;
  // a run of 64 total steps anneals faster: not the same weights
  o.stop_steps = 0;
  o.total_steps = 64;
  EXPECT_NE(policy::train_ppo(o, {}).actor.w.front(), ck[1].w.front());
}

TEST(PpoTrain, SuccessIsBootstrappedAsManiSkillDoesUnlessTerminalIsAsked) {
  using sim::SafetyFlag;
  EXPECT_TRUE(policy::bootstraps(true, false, SafetyFlag::kNone, true));    // success, ManiSkill
  EXPECT_FALSE(policy::bootstraps(true, false, SafetyFlag::kNone, false));  // success, terminal
  EXPECT_TRUE(policy::bootstraps(true, true, SafetyFlag::kNone, true));     // success at the time limit
  EXPECT_TRUE(policy::bootstraps(false, true, SafetyFlag::kNone, false));   // time limit
  EXPECT_TRUE(policy::bootstraps(false, true, SafetyFlag::kNone, true));
  EXPECT_FALSE(policy::bootstraps(false, false, SafetyFlag::kWorkspaceViolation, true));  // safety stop
  EXPECT_FALSE(policy::bootstraps(false, true, SafetyFlag::kWorkspaceViolation, true));
  EXPECT_FALSE(policy::bootstraps(true, false, SafetyFlag::kWorkspaceViolation, true));
}

TEST(PpoWarmStart, ActorStartsAsTheInitialBackboneWithItsNormalisationFoldedAndZeroHistoryWeights) {
  // a reactive push network with a non-identity input normalisation
  auto init = std::make_shared<policy::MlpWeights>(policy::MlpWeights::init(sim::TaskId::kPushCube, 0, {16, 16}, 5));
  for (int i = 0; i < init->input_dim(); ++i) {
    init->input_mean(i) = 0.1f * static_cast<float>(i % 5) - 0.2f;
    init->input_std(i) = 0.5f + 0.05f * static_cast<float>(i % 7);
  }
  for (auto& b : init->b) b.setConstant(0.03f);
  policy::PpoOptions o = tiny(1);
  o.init_actor = init;
  o.delay_aware = true;
  const int in = init->input_dim(), dim = in + 7 * policy::kHistoryLength;
  policy::PpoLearner learner(o, dim);
  Eigen::MatrixXf x = Eigen::MatrixXf::Random(dim, 3) * 0.3f;
  const Eigen::MatrixXf m = learner.mean(x);
  for (int c = 0; c < 3; ++c) {
    const Eigen::VectorXf obs = x.col(c).head(in);
    // mlp_forward clips to [-1, 1]; compare where the raw mean is inside
    const Action want = policy::mlp_forward(*init, obs);
    for (int j = 0; j < 7; ++j)
      if (std::abs(m(j, c)) < 0.99f) {
        EXPECT_NEAR(m(j, c), want(j), 1e-5) << "column " << c << " channel " << j;
      }
  }
  // the history inputs do not move the warm-started actor
  Eigen::MatrixXf y = x;
  y.bottomRows(7 * policy::kHistoryLength).setConstant(0.7f);
  EXPECT_TRUE(learner.mean(y).isApprox(m, 1e-6f));
  // a fresh learner differs; a wrong width or task is refused
  EXPECT_FALSE(policy::PpoLearner(tiny(1), in).mean(x.topRows(in)).isApprox(m, 1e-3f));
  auto bad = tiny(1);
  bad.init_actor = init;
  bad.hidden = {16, 8};
  EXPECT_THROW(policy::PpoLearner(bad, in), std::invalid_argument);
  bad = tiny(1);
  bad.init_actor = init;
  bad.task = sim::TaskId::kPullCube;
  EXPECT_THROW(policy::PpoLearner(bad, in), std::invalid_argument);
}

TEST(PpoWarmStart, CriticWarmupFreezesTheActorThenReleasesIt) {
  auto first = policy::train_ppo(tiny(1), {});
  auto init = std::make_shared<const policy::MlpWeights>(first.actor);
  auto o = tiny(1);
  o.init_actor = init;
  o.critic_warmup = 2;  // the whole (2-iteration) run
  o.eval_episodes = 0;
  const auto frozen = policy::train_ppo(o, {});
  EXPECT_EQ(frozen.actor.w, init->w);
  EXPECT_EQ(frozen.actor.b, init->b);
  o.critic_warmup = 1;  // the second iteration moves it
  const auto moved = policy::train_ppo(o, {});
  EXPECT_NE(moved.actor.w, init->w);
  // deterministic whatever the threads
  o.threads = 2;
  EXPECT_EQ(policy::serialize_mlp(policy::train_ppo(o, {}).actor), policy::serialize_mlp(moved.actor));
}

TEST(PpoTrain, RejectsNonPositiveSizes) {
  auto o = tiny(1);
  o.num_envs = 0;
  EXPECT_THROW(policy::train_ppo(o, {}), std::invalid_argument);
  o = tiny(1);
  o.num_minibatches = 1000;  // more minibatches than transitions
  EXPECT_THROW(policy::train_ppo(o, {}), std::invalid_argument);
}

}  // namespace
