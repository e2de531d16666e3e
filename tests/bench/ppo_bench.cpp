// One PPO update (the default 4 epochs x 2 minibatches of the default 64 x 16 rollout, actor and critic
// 3 x 256 tanh) on a fixed synthetic batch, with 1 and 2 gradient threads; and one rollout+update
// iteration of the real trainer on push_cube (environment steps included).
#include "actionshift/core/rng.hpp"
#include "actionshift/policy/ppo.hpp"
#include "actionshift/sim/task.hpp"

#include <benchmark/benchmark.h>

using namespace actionshift;

namespace {

policy::PpoBatch fixed_batch(int obs_dim, int n) {
  Rng rng(20260718);
  policy::PpoBatch b;
  b.obs.resize(obs_dim, n);
  b.actions.resize(7, n);
  b.log_probs.resize(n);
  b.advantages.resize(n);
  b.returns.resize(n);
  for (int k = 0; k < n; ++k) {
    for (int i = 0; i < obs_dim; ++i) b.obs(i, k) = static_cast<float>(rng.normal());
    for (int j = 0; j < 7; ++j) b.actions(j, k) = static_cast<float>(rng.normal(0.0, 0.6));
    b.advantages(k) = static_cast<float>(rng.normal());
    b.returns(k) = static_cast<float>(rng.uniform());
  }
  return b;
}

void BM_PpoUpdate(benchmark::State& state) {
  policy::PpoOptions o;  // defaults: 64 envs x 16 steps, 2 minibatches, 4 epochs, 3 x 256
  o.target_kl = 0;       // always the full 4 epochs: a fixed amount of work
  const int obs_dim = sim::observation_layout(sim::TaskId::kPickCube).size();
  policy::PpoLearner learner(o, obs_dim);
  policy::PpoBatch b = fixed_batch(obs_dim, o.num_envs * o.num_steps);
  b.log_probs = learner.log_prob(learner.mean(b.obs), b.actions);
  std::uint64_t seed = 1;
  for (auto _ : state) {
    auto s = learner.update(b, seed++, static_cast<unsigned>(state.range(0)));
    benchmark::DoNotOptimize(s);
  }
  state.counters["transitions/s"] =
      benchmark::Counter(static_cast<double>(b.size()) * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PpoUpdate)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PpoIteration(benchmark::State& state) {
  policy::PpoOptions o;
  o.task = sim::TaskId::kPushCube;
  o.total_steps = static_cast<std::int64_t>(o.num_envs) * o.num_steps;  // one iteration
  o.eval_episodes = 0;
  o.threads = static_cast<unsigned>(state.range(0));
  for (auto _ : state) {
    auto r = policy::train_ppo(o, {});
    benchmark::DoNotOptimize(r);
  }
  state.counters["env_steps/s"] = benchmark::Counter(static_cast<double>(o.total_steps) * static_cast<double>(state.iterations()),
                                                     benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PpoIteration)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
