// Google Benchmark for the sim layer: one control step with contact, reset, IK, and the
// throughput fixture `actionshift bench env` uses. Shared-model fixture (one immutable model, one Env per thread).
#include "actionshift/sim/bench.hpp"
#include "actionshift/sim/controller.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/grasp_script.hpp"

#include "actionshift/core/rng.hpp"

#include <benchmark/benchmark.h>

namespace {

using namespace actionshift;
using namespace actionshift::sim;

const std::shared_ptr<const EnvModel>& pick_model() {
  static const auto model = EnvModel::make(TaskId::kPickCube);
  return model;
}

// control steps of the scripted grasp-and-lift; a new seeded episode whenever one ends
void BM_PickCubeControlStep(benchmark::State& state) {
  Env env(pick_model());
  std::uint64_t episode = 0;
  env.reset(derive_seed({1, episode}));
  GraspLiftScript script;
  for (auto _ : state) {
    if (env.last().episode_over()) {
      state.PauseTiming();
      env.reset(derive_seed({1, ++episode}));
      script = GraspLiftScript();
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(env.step(script.act(env.snapshot())).reward);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PickCubeControlStep);

void BM_Reset(benchmark::State& state) {
  Env env(EnvModel::make(static_cast<TaskId>(state.range(0))));
  std::uint64_t seed = 0;
  for (auto _ : state) benchmark::DoNotOptimize(env.reset(++seed).data());
}
BENCHMARK(BM_Reset)->DenseRange(0, 4);

void BM_IkSolve(benchmark::State& state) {
  const KinematicChain& arm = pick_model()->arm();
  const Eigen::Matrix<double, 7, 1> q = pick_model()->rest_qpos().head<7>();
  Eigen::Matrix<double, 6, 1> a;
  a << 0.5, -0.3, 0.2, 0.1, 0.2, -0.4;
  const Eigen::Isometry3d target = target_pose(arm.fk(q), interpret_pose_command(a));
  for (auto _ : state) benchmark::DoNotOptimize(solve_ik(arm, q, target).error);
}
BENCHMARK(BM_IkSolve);

// the whole-episode throughput measured by `actionshift bench env` (items = control steps)
void BM_EnvThroughput(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    const EnvThroughput r = measure_env_throughput(TaskId::kPickCube, 500, threads);
    state.counters["steps_per_s"] = r.steps_per_s;
  }
}
BENCHMARK(BM_EnvThroughput)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
