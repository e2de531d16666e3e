// Decode/encode throughput. Budgets (issue 2): decode+encode of one 7-vector <= 50 ns;
// batched decode >= 20 million actions/s on one core.
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/core/transforms.hpp"

#include <benchmark/benchmark.h>

namespace {

using namespace actionshift;

// the hardest contract of the reference pool: absolute target and tool frame
const Contract& contract() {
  static const Contract c = reference::representative_contracts("unseen_composition")[0];
  return c;
}

void BM_DecodeEncodeOne(benchmark::State& state) {
  const Contract& c = contract();
  Mat3 R;
  R << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  Pose6 T = Pose6::Constant(0.01);
  Action x;
  x << 0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7;
  for (auto _ : state) {
    benchmark::DoNotOptimize(x);
    const Action raw = encode(c, x, R, T);
    Action back = decode(c, raw, R, T);
    benchmark::DoNotOptimize(back);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DecodeEncodeOne);

void BM_DecoderStepOne(benchmark::State& state) {
  auto f = contract().fields();
  f.lag = 2;
  Decoder d(Contract::make(f));
  Action raw;
  raw << 0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7;
  const Mat3 R = Mat3::Identity();
  for (auto _ : state) {
    benchmark::DoNotOptimize(raw);
    Action out = d.step(raw, R);
    benchmark::DoNotOptimize(out);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DecoderStepOne);

void BM_DecoderBatched(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  auto f = contract().fields();
  f.lag = static_cast<int>(state.range(1));
  Decoder d(Contract::make(f), n);
  Decoder::Batch raw = Decoder::Batch::Random(7, n), out(7, n);
  std::vector<Mat3> R(static_cast<std::size_t>(n), Mat3::Identity());
  for (auto _ : state) {
    d.step(raw, R, {}, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_DecoderBatched)->Args({1024, 0})->Args({1024, 2})->Args({16, 0});

}  // namespace

// parse_json_input on one object of N distinct keys: the duplicate-key check must stay linear in N
// (it compared each key with every earlier one: 200,000 keys took over a minute)
static void BM_ParseJsonManyKeys(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  std::string text = "{";
  for (int i = 0; i < n; ++i) text += (i ? ",\"k" : "\"k") + std::to_string(i) + "\":" + std::to_string(i);
  text += "}";
  for (auto _ : state) benchmark::DoNotOptimize(actionshift::parse_json_input(text, "bench"));
  state.SetComplexityN(n);
}
BENCHMARK(BM_ParseJsonManyKeys)->RangeMultiplier(10)->Range(2000, 200000)->Unit(benchmark::kMillisecond)->Complexity();
