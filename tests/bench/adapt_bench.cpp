// Per-environment-step cost of the pool belief and probe selection. Budgets: belief update <= 2 us
// for 9 hypotheses and <= 20 us for the full pool (issue 6); entropy selection <= 8 us and DualABI
// <= 15 us for 9 hypotheses, <= 60 us and <= 90 us for the full pool (issue 18). The batched belief
// is timed per call at 1, 8 and 1024 environments. scripts/bench_adapt_table regenerates the table
// in docs/results/benchmarks.md from this executable's JSON output. Grammar belief (issue 11): one update
// <= 20 us; one action selection (MAP resolution over the 8 modes and the encode) and one entropy-probe
// selection <= 200 us each; the scale corrector's Ceres fit of one channel (16-step window) is timed too.
#include "actionshift/adapt/batched_belief.hpp"
#include "actionshift/adapt/grammar_belief.hpp"
#include "actionshift/adapt/methods.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/data/builtin_manifests.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

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

// one entropy-probe selection of the grammar belief (12 pulses, every cell's posterior moments)
void BM_GrammarEntropySelect(benchmark::State& state) {
  GrammarBelief b(kModel);
  Decoder env(reference::representative_contracts("seen")[1]);
  for (int k = 0; k < 3; ++k) {
    const Action raw = GrammarBelief::probe_candidate(k, 0.5);
    b.update(raw, kModel.expected(env.step(raw)));
  }
  for (auto _ : state) benchmark::DoNotOptimize(b.select_entropy_probe(0.5));
}
BENCHMARK(BM_GrammarEntropySelect);

// one update with the scale corrector on (amortised over its window: every 16th update fits)
void BM_GrammarUpdateCorrected(benchmark::State& state) {
  GrammarBelief b(kModel, ScaleCorrectorOptions{});
  Decoder env(reference::representative_contracts("seen")[1]);
  int k = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const Action raw = b.map_encode(intent(k++));
    const Pose6 obs = kModel.expected(env.step(raw));
    state.ResumeTiming();
    b.update(raw, obs);
    if (k % 200 == 0) b.reset();
  }
  state.SetLabel(std::to_string(b.corrector()->fits()) + " channel fits since the last reset");
}
BENCHMARK(BM_GrammarUpdateCorrected);

// one Ceres least-squares fit of one channel over a 16-step window
void BM_ScaleFitCeres(benchmark::State& state) {
  std::vector<double> c(16), o(16);
  for (std::size_t t = 0; t < c.size(); ++t) {
    c[t] = 0.2 + 0.05 * static_cast<double>(t % 7);
    o[t] = 0.03 * 1.1 * c[t] * (1.0 + 0.01 * std::sin(static_cast<double>(t)));
  }
  for (auto _ : state) benchmark::DoNotOptimize(fit_window_gain(c, o, 0.03, 1.0, 0.4, 2.5));
}
BENCHMARK(BM_ScaleFitCeres)->Unit(benchmark::kMicrosecond);
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
