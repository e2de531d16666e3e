// Diffusion Policy DDPM: the squaredcos_cap_v2 schedule against its closed form, the reverse step,
// the samplers, the trainer's schedules, learning on a toy problem, and byte-identical training with
// 1 and 2 threads
#include "actionshift/core/rng.hpp"
#include "actionshift/policy/dp.hpp"

#include "actionshift/core/error.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <vector>

namespace actionshift::policy {
namespace {

double alpha_bar(double t) { return std::pow(std::cos((t + 0.008) / 1.008 * std::numbers::pi / 2), 2); }

TEST(DdpmSchedule, SquaredcosCapV2MatchesClosedForm) {
  const DdpmSchedule s = DdpmSchedule::squaredcos_cap_v2(100);
  ASSERT_EQ(s.steps(), 100);
  double prod = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double beta = std::min(1.0 - alpha_bar((i + 1) / 100.0) / alpha_bar(i / 100.0), 0.999);
    prod *= 1.0 - beta;
    EXPECT_NEAR(s.betas[static_cast<std::size_t>(i)], beta, 1e-15) << i;
    EXPECT_NEAR(s.alphas_cumprod[static_cast<std::size_t>(i)], prod, 1e-15) << i;
    // the product telescopes: alphas_cumprod_i = alpha_bar((i+1)/T) / alpha_bar(0) while beta is not capped
    if (i < 99) {
      EXPECT_NEAR(s.alphas_cumprod[static_cast<std::size_t>(i)], alpha_bar((i + 1) / 100.0) / alpha_bar(0.0), 1e-12) << i;
    }
  }
  // golden values (computed separately in Python from the same formula)
  EXPECT_NEAR(s.betas[0], 0.0006312815983416931, 1e-15);
  EXPECT_NEAR(s.betas[50], 0.03154633936072582, 1e-14);
  EXPECT_NEAR(s.betas[98], 0.7499392803846627, 1e-13);
  EXPECT_EQ(s.betas[99], 0.999);  // capped
  EXPECT_NEAR(s.alphas_cumprod[50], 0.4782646329454781, 1e-13);
  EXPECT_NEAR(s.alphas_cumprod[99], 2.4285722793500615e-07, 1e-18);
  EXPECT_THROW(DdpmSchedule::squaredcos_cap_v2(0), std::invalid_argument);
}

TEST(DdpmStep, PosteriorMeanVarianceAndClip) {
  const DdpmSchedule s = DdpmSchedule::squaredcos_cap_v2(100);
  Rng rng(1);
  DpMat<float> x0(3, 4), eps(3, 4), noise(3, 4);
  for (int i = 0; i < 12; ++i) {
    x0(i) = static_cast<float>(rng.uniform(-0.9, 0.9));
    eps(i) = static_cast<float>(rng.normal());
    noise(i) = static_cast<float>(rng.normal());
  }
  for (int t : {1, 37, 99}) {
    const double ab = s.alphas_cumprod[static_cast<std::size_t>(t)], ab_prev = s.alphas_cumprod[static_cast<std::size_t>(t - 1)];
    const double beta = s.betas[static_cast<std::size_t>(t)];
    const DpMat<float> xt = (std::sqrt(ab) * x0.cast<double>() + std::sqrt(1 - ab) * eps.cast<double>()).cast<float>();
    // q(x_{t-1} | x_t, x_0): mean and variance of Ho et al. (2020), eq. 7
    const Eigen::MatrixXd mean =
        std::sqrt(ab_prev) * beta / (1 - ab) * x0.cast<double>() + std::sqrt(1 - beta) * (1 - ab_prev) / (1 - ab) * xt.cast<double>();
    const double var = (1 - ab_prev) / (1 - ab) * beta;
    const DpMat<float> prev = ddpm_step(s, t, xt, eps, noise);
    EXPECT_LT((prev.cast<double>() - (mean + std::sqrt(var) * noise.cast<double>())).cwiseAbs().maxCoeff(), 2e-4) << t;
  }
  // t = 0 returns the (clipped) clean estimate, without noise
  const DpMat<float> big = DpMat<float>::Constant(3, 4, 5.0f);
  const DpMat<float> out = ddpm_step(s, 0, big, DpMat<float>::Zero(3, 4), noise);
  EXPECT_EQ(out.maxCoeff(), 1.0f);
  EXPECT_EQ(out.minCoeff(), 1.0f);
  const DpMat<float> unclipped = ddpm_step(s, 0, big, DpMat<float>::Zero(3, 4), noise, false);
  EXPECT_NEAR(unclipped(0, 0), 5.0 / std::sqrt(s.alphas_cumprod[0]), 1e-4);
}

DpArch toy_arch() {
  DpArch a;
  a.action_dim = 2;
  a.obs_dim = 3;
  a.obs_horizon = 2;
  a.pred_horizon = 8;
  a.act_horizon = 4;
  a.step_embed_dim = 16;
  a.down_dims = {16, 32};
  a.kernel_size = 3;
  a.groups = 4;
  return a;
}

TEST(DpSample, DeterministicAndInRange) {
  const DpArch arch = toy_arch();
  const DpUnet<float> net(arch);
  const auto p = net.init(5);
  const DdpmSchedule s = DdpmSchedule::squaredcos_cap_v2(arch.diffusion_steps);
  const DpVec<float> cond = DpVec<float>::Constant(6, 0.3f);
  auto ws = net.workspace();
  for (int ddim : {0, 10}) {
    Rng r1(9), r2(9);
    const DpMat<float> a = dp_sample(net, p.data(), s, cond, r1, *ws, ddim);
    const DpMat<float> b = dp_sample(net, p.data(), s, cond, r2, *ws, ddim);
    EXPECT_EQ(a, b);
    EXPECT_EQ(a.rows(), 2);
    EXPECT_EQ(a.cols(), 8);
    EXPECT_LE(a.cwiseAbs().maxCoeff(), 1.0f);  // the last step returns the clipped clean estimate
  }
  Rng r(1);
  EXPECT_THROW(dp_sample(net, p.data(), s, cond, r, *ws, 101), std::invalid_argument);
}

TEST(DpLearner, LearningRateAndEmaSchedules) {
  DpLearnOptions o;
  o.warmup_steps = 10;
  o.total_steps = 110;
  const DpLearner l(toy_arch(), o, 1);
  EXPECT_EQ(l.learning_rate(1), 0.0);  // diffusers: the first step of the warm-up has step size 0
  EXPECT_NEAR(l.learning_rate(6), 0.5e-4, 1e-15);
  EXPECT_NEAR(l.learning_rate(11), 1e-4, 1e-15);
  EXPECT_NEAR(l.learning_rate(61), 0.5e-4, 1e-12);  // half way through the cosine
  EXPECT_NEAR(l.learning_rate(111), 0.0, 1e-15);
  EXPECT_EQ(l.ema_decay(1), 0.0);
  EXPECT_NEAR(l.ema_decay(2), 2.0 / 11.0, 1e-15);
  EXPECT_NEAR(l.ema_decay(101), 101.0 / 110.0, 1e-15);
  EXPECT_EQ(l.ema_decay(10000000), 0.9999);
}

// a toy imitation problem: the clean chunk is a fixed function of the condition's sign
struct ToyData {
  std::vector<DpMat<float>> actions;
  std::vector<DpVec<float>> conds;
};
DpMat<float> toy_chunk(bool up) {
  DpMat<float> c(2, 8);
  for (int t = 0; t < 8; ++t) {
    c(0, t) = (up ? 0.8f : -0.8f) * static_cast<float>(t) / 7.0f;
    c(1, t) = up ? 0.5f : -0.5f;
  }
  return c;
}
ToyData toy_batch(int n) {
  ToyData d;
  for (int k = 0; k < n; ++k) {
    const bool up = k % 2 == 0;
    d.actions.push_back(toy_chunk(up));
    d.conds.push_back(DpVec<float>::Constant(6, up ? 1.0f : -1.0f));
  }
  return d;
}

TEST(DpLearner, LearnsAToyConditionalDistribution) {
  DpLearnOptions o;
  o.learning_rate = 2e-3;
  o.warmup_steps = 5;
  DpLearner l(toy_arch(), o, 3);
  const ToyData d = toy_batch(32);
  double first = 0, last = 0;
  const int steps = 400;
  for (int i = 0; i < steps; ++i) {
    const double loss = l.step(d.actions, d.conds, 2);
    ASSERT_TRUE(std::isfinite(loss));
    if (i >= 5 && i < 25) first += loss / 20;
    if (i >= steps - 20) last += loss / 20;
  }
  std::printf("toy noise-prediction loss: %.4f -> %.4f\n", first, last);
  EXPECT_LT(last, 0.5 * first);
  // the EMA weights sample the chunk of each condition (DDPM, 100 steps; mean over 4 draws)
  auto ws = l.net().workspace();
  for (bool up : {true, false}) {
    double err = 0;
    for (int r = 0; r < 4; ++r) {
      Rng rng(static_cast<std::uint64_t>(10 + r));
      const DpMat<float> a = dp_sample(l.net(), l.ema().data(), l.schedule(), DpVec<float>::Constant(6, up ? 1.0f : -1.0f), rng, *ws);
      err += (a - toy_chunk(up)).cwiseAbs().mean() / 4;
    }
    std::printf("toy sample (%s) mean abs error %.3f\n", up ? "up" : "down", err);
    EXPECT_LT(err, 0.15);
  }
}

TEST(DpLearner, SameBytesWithOneAndTwoThreads) {
  const ToyData d = toy_batch(13);  // uneven shards
  DpLearnOptions o;
  o.shards = 4;
  o.warmup_steps = 2;
  DpLearner a(toy_arch(), o, 77), b(toy_arch(), o, 77);
  for (int i = 0; i < 4; ++i) {
    const double la = a.step(d.actions, d.conds, 1);
    const double lb = b.step(d.actions, d.conds, 2);
    EXPECT_EQ(std::memcmp(&la, &lb, sizeof la), 0) << i;
  }
  ASSERT_EQ(a.params().size(), b.params().size());
  EXPECT_EQ(std::memcmp(a.params().data(), b.params().data(), a.params().size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(a.ema().data(), b.ema().data(), a.ema().size() * sizeof(float)), 0);
  // and the weights moved
  const DpLearner fresh(toy_arch(), o, 77);
  EXPECT_NE(std::memcmp(a.params().data(), fresh.params().data(), a.params().size() * sizeof(float)), 0);
}

// train_dp with a checkpoint: a run stopped after its checkpoint at iteration 4 and started again
// ends with the bytes of a run never stopped (weights, EMA, final loss, curve); a checkpoint of other
// settings or a damaged one is refused with the file named
TEST(TrainDp, AnInterruptedRunContinuesFromItsCheckpointToTheSameBytes) {
  TrainDpOptions o;
  o.demos = 2;
  o.iterations = 6;
  o.batch_size = 4;
  o.down_dims = {8, 16};
  o.threads = 1;
  o.log_every = 1;
  const TrainDpResult whole = train_dp(o);
  const std::string want = serialize_dp(whole.weights);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("as_dp_ckpt_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  o.checkpoint = (dir / "run.ckpt").string();
  o.checkpoint_every = 2;
  struct Stop {};
  EXPECT_THROW(train_dp(o, [](const TrainDpProgress& p) { if (p.iteration == 5) throw Stop{}; }), Stop);
  ASSERT_TRUE(std::filesystem::exists(o.checkpoint));
  const TrainDpResult resumed = train_dp(o);
  EXPECT_EQ(resumed.resumed_at, 4);
  EXPECT_EQ(serialize_dp(resumed.weights), want);
  EXPECT_EQ(std::memcmp(&resumed.final_loss, &whole.final_loss, sizeof(double)), 0);
  ASSERT_EQ(resumed.curve.size(), whole.curve.size());
  for (std::size_t i = 0; i < whole.curve.size(); ++i) {
    EXPECT_EQ(resumed.curve[i].iteration, whole.curve[i].iteration);
    EXPECT_EQ(resumed.curve[i].loss, whole.curve[i].loss) << i;
  }

  // the checkpoint of iteration 4 is still there (the caller removes it): other settings refuse it
  TrainDpOptions other = o;
  other.seed += 1;
  EXPECT_THAT([&] { train_dp(other); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr(o.checkpoint + ": settings_sha256")));
  // a damaged one is named, not trusted
  std::string bytes;
  {
    std::ifstream in(o.checkpoint, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  bytes[bytes.size() - 3] ^= 0x5a;
  std::ofstream(o.checkpoint, std::ios::binary | std::ios::trunc) << bytes;
  EXPECT_THAT([&] { train_dp(o); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr(o.checkpoint + ": payload: checksum mismatch")));
  std::ofstream(o.checkpoint, std::ios::binary | std::ios::trunc) << "not a checkpoint";
  EXPECT_THAT([&] { train_dp(o); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr(o.checkpoint + ": magic")));
  o.checkpoint_every = 0;
  EXPECT_THAT([&] { check_train_dp_options(o); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("checkpoint-every")));
  std::filesystem::remove_all(dir);
}

// Eigen blocks a product's depth by a length it derives from the L1 cache size, so the same training
// rounds differently on machines with other caches (the learner alone shows it); train_dp fixes the
// size it assumes, so its bytes are the same whatever the caller's (or the CPU's) setting, and it
// gives the caller's setting back
TEST(TrainDp, BytesDoNotDependOnTheMachinesL1Cache) {
  const std::ptrdiff_t l1 = Eigen::l1CacheSize(), l2 = Eigen::l2CacheSize(), l3 = Eigen::l3CacheSize();
  DpArch arch = toy_arch();
  arch.down_dims = {8, 240};  // depth 240 x 3 = 720: blocked under a 32 KiB L1 (680), not under 48 KiB (1,016)
  const ToyData d = toy_batch(6);
  std::vector<std::vector<float>> learned;
  for (const std::ptrdiff_t cache : {std::ptrdiff_t{32 * 1024}, std::ptrdiff_t{48 * 1024}}) {
    Eigen::setCpuCacheSizes(cache, l2, l3);
    DpLearnOptions o;
    o.warmup_steps = 0;
    DpLearner learner(arch, o, 5);
    for (int i = 0; i < 2; ++i) learner.step(d.actions, d.conds, 1);
    learned.push_back(learner.params());
  }
  EXPECT_NE(std::memcmp(learned[0].data(), learned[1].data(), learned[0].size() * sizeof(float)), 0)
      << "the two cache sizes should block the depth differently";

  TrainDpOptions o;
  o.demos = 2;
  o.iterations = 3;
  o.batch_size = 4;
  o.down_dims = {8, 144};  // depth 144 x 5 = 720, as above
  o.threads = 1;
  std::vector<std::string> bytes;
  for (const std::ptrdiff_t cache : {std::ptrdiff_t{48 * 1024}, std::ptrdiff_t{32 * 1024}, std::ptrdiff_t{64 * 1024}}) {
    Eigen::setCpuCacheSizes(cache, l2, l3);
    bytes.push_back(serialize_dp(train_dp(o).weights));
    EXPECT_EQ(Eigen::l1CacheSize(), cache) << "train_dp gives the caller's L1 size back";
  }
  EXPECT_TRUE(bytes[0] == bytes[1]) << "train_dp under a 32 KiB L1 differs from under 48 KiB";
  EXPECT_TRUE(bytes[0] == bytes[2]) << "train_dp under a 64 KiB L1 differs from under 48 KiB";
  Eigen::setCpuCacheSizes(l1, l2, l3);
}

// The committed pick_cube Diffusion Policy's own recipe, run to its first logged loss (iteration 50,
// the mean of 50 minibatch losses): the bits must be the committed curve's, or the file cannot
// re-train byte for byte (scripts/ppo_reproduce runs all 30,000 iterations, about 3.5 hours). About
// 35 s on two cores: 1,000 expert demonstrations and 50 steps of the 4.39 M-parameter U-Net.
TEST(TrainDp, ReproducesTheFirstLossOfTheCommittedPickCubeCurve) {
  std::ifstream curve(ACTIONSHIFT_SOURCE_DIR "/docs/results/dp_pick_cube.curve.jsonl");
  ASSERT_TRUE(curve.good());
  std::string line;
  std::getline(curve, line);
  const nlohmann::json first = nlohmann::json::parse(line);
  ASSERT_EQ(first.at("iteration").get<int>(), 50);
  const double want = first.at("loss").get<double>();
  TrainDpOptions o;  // the header's command: train dp --task pick_cube --seed 20260718 --demos 1000
  o.task = sim::TaskId::kPickCube;  //   --iterations 30000 --batch 64 --down-dims 64,128,256 --lr 1e-4
  o.seed = 20260718;
  o.demos = 1000;
  o.iterations = 30000;
  o.batch_size = 64;
  o.down_dims = {64, 128, 256};
  o.learn.learning_rate = 1e-4;
  o.profile = "maniskill";
  o.threads = 0;
  struct Stop {};
  double got = 0.0;
  EXPECT_THROW(train_dp(o,
                        [&](const TrainDpProgress& p) {
                          got = p.loss;
                          throw Stop{};
                        }),
               Stop);
  std::printf("iteration 50: loss %.17g (committed curve %.17g)\n", got, want);
  EXPECT_EQ(std::memcmp(&got, &want, sizeof got), 0) << "got " << got << ", the committed curve " << want;
}

TEST(DpLearner, RejectsBadBatches) {
  DpLearner l(toy_arch(), {}, 1);
  EXPECT_THROW(l.step({}, {}, 1), std::invalid_argument);
  EXPECT_THROW(l.step({DpMat<float>::Zero(2, 4)}, {DpVec<float>::Zero(6)}, 1), std::invalid_argument);
}

}  // namespace
}  // namespace actionshift::policy
