// Per-environment-step cost of the pool belief and probe selection. Budgets: belief update <= 2 us
// for 9 hypotheses and <= 20 us for the full pool (issue 6); entropy selection <= 8 us and DualABI
// <= 15 us for 9 hypotheses, <= 60 us and <= 90 us for the full pool (issue 18). The batched belief
// is timed per call at 1, 8 and 1024 environments. scripts/bench_adapt_table regenerates the table
// in docs/results/benchmarks.md from this executable's JSON output. Grammar belief (issue 11): one update
// <= 20 us; one action selection (MAP resolution over the 8 modes and the encode) <= 200 us.
#include "actionshift/adapt/batched_belief.hpp"
#include "actionshift/adapt/grammar_belief.hpp"
#include "actionshift/adapt/methods.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/data/builtin_manifests.hpp"

#include <benchmark/benchmark.h>

#include <cmath>

namespace {

using namespace actionshift;
using namespace actionshift::adapt;

const ResponseModel kModel{{0.032, 0.016, 0.018, -0.035, -0.027, -0.038}, {0.03, 0.02, 0.02, 0.04, 0.05, 0.04}};

std::vector<Contract> pool(int which) {
  return which == 0 ? reference::pool9() : data::resolve_manifest("full").contracts();
}

Action intent(int k) {
  Action a;
  for (int c = 0; c < 7; ++c) a[c] = 0.9 * std::sin(k + c);
  return a;
}

void BM_BeliefUpdate(benchmark::State& state) {
  PoolBelief b(pool(static_cast<int>(state.range(0))), kModel);
  const Contract truth = reference::oracle_contract();
  Decoder env(truth);
  int k = 0;
  for (auto _ : state) {
    const Action raw = intent(k++);
    const Pose6 obs = kModel.expected(env.step(raw));
    b.update(raw, obs, Mat3::Identity());
    if (k % 50 == 0) b.reset();  // stay in the informative regime
  }
  state.SetLabel(std::to_string(b.size()) + " hypotheses");
}
BENCHMARK(BM_BeliefUpdate)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// selection from a fresh (uniform) belief: the most expensive point of an episode
void BM_EntropySelect(benchmark::State& state) {
  ProbingAdapter p(pool(static_cast<int>(state.range(0))), kModel, ProbeStrategy::kEntropy);
  for (auto _ : state) {
    p.begin_episode(1);
    Action raw = p.encode(intent(0), Mat3::Identity());
    benchmark::DoNotOptimize(raw);
  }
  state.SetLabel(std::to_string(p.belief().size()) + " hypotheses");
}
BENCHMARK(BM_EntropySelect)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_DualAbiSelect(benchmark::State& state) {
  DualAbiAdapter d(pool(static_cast<int>(state.range(0))), kModel, 0.0);
  for (auto _ : state) {
    d.begin_episode(1);
    Action raw = d.encode(intent(0), Mat3::Identity());
    benchmark::DoNotOptimize(raw);
  }
  state.SetLabel(std::to_string(d.belief().size()) + " hypotheses");
}
BENCHMARK(BM_DualAbiSelect)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);


void BM_GrammarUpdate(benchmark::State& state) {
  GrammarBelief b(kModel);
  Decoder env(reference::representative_contracts("unseen_composition")[1]);
  int k = 0;
  for (auto _ : state) {
    const Action raw = intent(k++);
    b.update(raw, kModel.expected(env.step(raw)));
    if (k % 50 == 0) b.reset();
  }
  benchmark::DoNotOptimize(b.evidence(0, 0, 0, 0, 0));
}
BENCHMARK(BM_GrammarUpdate);

// one step's action selection: the MAP is stale after every update, so each iteration resolves it
// (8 modes: best sign/scale per cell and an exact 6x6 assignment) and encodes
void BM_GrammarSelect(benchmark::State& state) {
  GrammarBelief b(kModel);
  Decoder env(reference::representative_contracts("seen")[1]);
  for (int k = 0; k < 20; ++k) {
    const Action raw = intent(k);
    b.update(raw, kModel.expected(env.step(raw)));
  }
  int k = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const Action raw = intent(k++);
    b.update(raw, kModel.expected(env.step(raw)));
    state.ResumeTiming();
    benchmark::DoNotOptimize(b.map_encode(intent(k), false));
  }
}
BENCHMARK(BM_GrammarSelect);
// one batched update of n environments (inputs precomputed: a 50-step episode per environment)
void BM_BatchedBeliefUpdate(benchmark::State& state) {
  const int n = static_cast<int>(state.range(1));
  constexpr int kSteps = 50;
  BatchedPoolBelief b(pool(static_cast<int>(state.range(0))), kModel, n);
  Decoder env(reference::oracle_contract(), n);
  std::vector<BatchedPoolBelief::Batch> raw(kSteps, BatchedPoolBelief::Batch(kActionDim, n));
  std::vector<BatchedPoolBelief::PoseBatch> obs(kSteps, BatchedPoolBelief::PoseBatch(kPoseDim, n));
  BatchedPoolBelief::Batch exec(kActionDim, n);
  for (int k = 0; k < kSteps; ++k) {
    for (int e = 0; e < n; ++e) raw[static_cast<std::size_t>(k)].col(e) = intent(k + e);
    env.step(raw[static_cast<std::size_t>(k)], {}, {}, exec);
    for (int e = 0; e < n; ++e) obs[static_cast<std::size_t>(k)].col(e) = kModel.expected(exec.col(e));
  }
  int k = 0;
  for (auto _ : state) {
    b.update(raw[static_cast<std::size_t>(k)], obs[static_cast<std::size_t>(k)]);
    if (++k == kSteps) {
      k = 0;
      b.reset();
    }
  }
  state.SetItemsProcessed(state.iterations() * n);  // environment steps
  state.SetLabel(std::to_string(b.size()) + " hypotheses x " + std::to_string(n) + " envs");
}
BENCHMARK(BM_BatchedBeliefUpdate)
    ->ArgsProduct({{0, 1}, {1, 8, 1024}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
