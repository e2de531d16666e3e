// Diffusion Policy costs on the CPU: one sampled chunk (100 DDPM steps, or 10 DDIM steps), one control
// step of the policy averaged over its receding horizon (one chunk per 8 steps), and one training step
// (batch 64) with 1 and 2 threads; for the paper's network (down dims 64/128/256, 4.39 M parameters)
// and the scaled one (32/64/128, 1.26 M). Random weights: the cost does not depend on their values.
#include "actionshift/policy/dp.hpp"

#include <benchmark/benchmark.h>

using namespace actionshift;
using namespace actionshift::policy;

namespace {

DpArch arch_of(int variant) {
  DpArch a;  // pick_cube: obs 42 x 2, action 7, horizon 16, execute 8
  if (variant == 1) a.down_dims = {32, 64, 128};
  return a;
}

std::shared_ptr<const DpWeights> weights_of(int variant, int ddim) {
  auto w = std::make_shared<DpWeights>();
  w->task = sim::TaskId::kPickCube;
  w->arch = arch_of(variant);
  w->ddim_steps = ddim;
  w->obs_mean = Eigen::VectorXf::Zero(42);
  w->obs_std = Eigen::VectorXf::Ones(42);
  w->params = DpUnet<float>(w->arch).init(1);
  return w;
}

void label(benchmark::State& state) {
  state.SetLabel(std::string(state.range(0) == 0 ? "64/128/256" : "32/64/128") +
                 (state.range(1) == 0 ? " DDPM-100" : " DDIM-" + std::to_string(state.range(1))));
}

void BM_DpForward(benchmark::State& state) {
  const DpUnet<float> net(arch_of(static_cast<int>(state.range(0))));
  const auto p = net.init(1);
  auto ws = net.workspace();
  const DpMat<float> x = DpMat<float>::Random(7, 16);
  const DpVec<float> c = DpVec<float>::Random(84);
  for (auto _ : state) benchmark::DoNotOptimize(net.forward(p.data(), x, 50, c, *ws));
  state.SetLabel(state.range(0) == 0 ? "64/128/256" : "32/64/128");
}
BENCHMARK(BM_DpForward)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_DpChunk(benchmark::State& state) {
  const auto w = weights_of(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const DpUnet<float> net(w->arch);
  const DdpmSchedule s = DdpmSchedule::squaredcos_cap_v2(100);
  auto ws = net.workspace();
  const DpVec<float> c = DpVec<float>::Random(84);
  Rng rng(1);
  for (auto _ : state) benchmark::DoNotOptimize(dp_sample(net, w->params.data(), s, c, rng, *ws, w->ddim_steps));
  label(state);
}
BENCHMARK(BM_DpChunk)->Args({0, 0})->Args({0, 10})->Args({1, 0})->Args({1, 10})->Unit(benchmark::kMillisecond);

// per control step: act() in a loop, re-planning every act_horizon = 8 steps
void BM_DpControlStep(benchmark::State& state) {
  const auto w = weights_of(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  DpPolicy p(w, std::string(64, '0'), "dp:bench");
  p.reset();
  Eigen::VectorXd obs = Eigen::VectorXd::Zero(42);
  std::int64_t k = 0;
  for (auto _ : state) {
    obs(0) = 1e-3 * static_cast<double>(k++);
    benchmark::DoNotOptimize(p.act(obs));
  }
  state.counters["chunks/step"] = static_cast<double>(p.chunks_sampled()) / static_cast<double>(state.iterations());
  label(state);
}
BENCHMARK(BM_DpControlStep)->Args({0, 0})->Args({0, 10})->Args({1, 0})->Args({1, 10})->Iterations(64)->Unit(benchmark::kMillisecond);

void BM_DpTrainStep(benchmark::State& state) {
  DpLearnOptions o;
  o.warmup_steps = 0;
  DpLearner l(arch_of(static_cast<int>(state.range(0))), o, 1);
  std::vector<DpMat<float>> a(64, DpMat<float>::Random(7, 16) * 0.5f);
  std::vector<DpVec<float>> c(64, DpVec<float>::Random(84));
  for (auto _ : state) benchmark::DoNotOptimize(l.step(a, c, static_cast<unsigned>(state.range(1))));
  state.counters["samples/s"] = benchmark::Counter(64.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.SetLabel(std::string(state.range(0) == 0 ? "64/128/256" : "32/64/128") + " batch 64");
}
BENCHMARK(BM_DpTrainStep)->Args({0, 1})->Args({0, 2})->Args({1, 1})->Args({1, 2})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
