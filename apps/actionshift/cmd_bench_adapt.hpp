#pragma once
// actionshift bench adapt (cmd_bench_adapt.cpp, adapt layer)
#include "actionshift/adapt/bench.hpp"

#include <string>

namespace actionshift::cli {

struct BenchAdaptOptions {
  /// Bound directly: --method, --episodes, --steps, --repetitions, --seed (checked once, by
  /// adapt::bench_adapter); `params`, `pool` and `model` are set from the options below.
  adapt::AdapterBenchConfig bench = [] {
    adapt::AdapterBenchConfig c;
    c.method = "entropy_probes";
    return c;
  }();
  std::string pool = "reference9";        ///< pool name or file (pool methods)
  std::string params = "{}";              ///< method parameters, a JSON object
  std::string task = "pick_cube";         ///< whose built-in calibration is the response model
  std::string profile = "maniskill";      ///< simulator fidelity profile of that calibration
  bool json = false;
};
int run_bench_adapt(const BenchAdaptOptions& o);

}  // namespace actionshift::cli
