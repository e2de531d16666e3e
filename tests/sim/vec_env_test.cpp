// sim::VecEnv, the vectorised environment of PPO and the Python module's make_vec: each environment
// steps exactly as the same HiddenContractEnv stepped alone, whatever the number of threads; a new
// contract takes effect from the next reset; a wrong number of actions or no environments is refused.
#include "actionshift/sim/vec_env.hpp"

#include "actionshift/core/rng.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <vector>

using namespace actionshift;
using namespace actionshift::sim;

namespace {

Contract lagged(int lag, long long sign0 = 1) {
  ContractFields f;
  f.lag = lag;
  f.sign[0] = sign0;
  return Contract::make(f);
}

// observations after each of `steps` steps of every environment, flattened in environment order
std::vector<double> roll(VecEnv& v, int steps, std::uint64_t seed) {
  std::vector<double> out;
  v.for_each([&](int i) { v.env(i).reset(seed + static_cast<std::uint64_t>(i)); });
  Rng rng(11);
  std::vector<double> actions(static_cast<std::size_t>(7 * v.size()));
  std::vector<std::vector<double>> obs(static_cast<std::size_t>(v.size()));
  for (int t = 0; t < steps; ++t) {
    for (double& a : actions) a = rng.uniform(-0.6, 0.6);
    v.step(actions, [&](int i, const StepResult& r) {
      obs[static_cast<std::size_t>(i)].assign(r.obs.data(), r.obs.data() + r.obs.size());
      obs[static_cast<std::size_t>(i)].push_back(r.reward);
    });
    for (const auto& o : obs) out.insert(out.end(), o.begin(), o.end());
  }
  return out;
}

}  // namespace

TEST(VecEnv, EachEnvironmentStepsAsItWouldAloneWhateverTheThreads) {
  const auto model = EnvModel::make(TaskId::kPushCube);
  const std::vector<Contract> cs{Contract::identity(), lagged(2), lagged(0, -1), lagged(1, -1), Contract::identity()};
  VecEnv one(model, cs, FrameRotation::kLive, 1), two(model, cs, FrameRotation::kLive, 2);
  EXPECT_EQ(one.threads(), 1u);
  EXPECT_EQ(two.threads(), 2u);
  const std::vector<double> a = roll(one, 12, 40), b = roll(two, 12, 40);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * a.size()), 0);

  // the same actions, one HiddenContractEnv at a time
  std::vector<HiddenContractEnv> alone;
  for (const auto& c : cs) alone.emplace_back(model, c);
  for (std::size_t i = 0; i < alone.size(); ++i) alone[i].reset(40 + i);
  Rng rng(11);
  std::vector<double> ref;
  for (int t = 0; t < 12; ++t) {
    std::vector<double> actions(7 * alone.size());
    for (double& x : actions) x = rng.uniform(-0.6, 0.6);
    for (std::size_t i = 0; i < alone.size(); ++i) {
      const StepResult& r = alone[i].step(std::span<const double>(actions.data() + 7 * i, 7));
      ref.insert(ref.end(), r.obs.data(), r.obs.data() + r.obs.size());
      ref.push_back(r.reward);
    }
  }
  ASSERT_EQ(ref.size(), a.size());
  EXPECT_EQ(std::memcmp(ref.data(), a.data(), sizeof(double) * a.size()), 0);
}

TEST(VecEnv, ANewContractTakesEffectFromTheNextReset) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  VecEnv v(model, {Contract::identity(), Contract::identity()}, FrameRotation::kLive, 2);
  v.set_contract(1, lagged(0, -1));
  HiddenContractEnv flipped(model, lagged(0, -1)), plain(model, Contract::identity());
  v.for_each([&](int i) { v.env(i).reset(7); });
  flipped.reset(7);
  plain.reset(7);
  std::vector<double> actions(14, 0.0);
  actions[0] = actions[7] = 0.5;  // +x for both
  std::vector<Eigen::VectorXd> obs(2);
  v.step(actions, [&](int i, const StepResult& r) { obs[static_cast<std::size_t>(i)] = r.obs; });
  Action a = Action::Zero();
  a(0) = 0.5;
  EXPECT_EQ(obs[0], plain.step(a).obs);
  EXPECT_EQ(obs[1], flipped.step(a).obs);
  EXPECT_NE(obs[0], obs[1]);
}

TEST(VecEnv, RefusesAWrongNumberOfActionsAndNoEnvironments) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  EXPECT_THROW(VecEnv(model, {}, FrameRotation::kLive, 1), std::invalid_argument);
  VecEnv v(model, {Contract::identity(), Contract::identity(), Contract::identity()}, FrameRotation::kLive, 8);
  EXPECT_EQ(v.threads(), 3u);  // at most one worker per environment
  v.for_each([&](int i) { v.env(i).reset(1); });
  std::vector<double> short_(20, 0.0);
  try {
    v.step(short_, [](int, const StepResult&) {});
    FAIL() << "20 numbers for 3 environments were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("expected 21"), std::string::npos) << e.what();
  }
}
