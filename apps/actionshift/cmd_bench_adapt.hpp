#pragma once
// actionshift bench adapt (cmd_bench_adapt.cpp, adapt layer)
#include <cstdint>
#include <string>

namespace actionshift::cli {

struct BenchAdaptOptions {
  std::string method = "entropy_probes";  ///< a method name (docs/adapters.md)
  std::string pool = "reference9";        ///< pool name or file (pool methods)
  std::string params = "{}";              ///< method parameters, a JSON object
  std::string task = "pick_cube";         ///< whose built-in calibration is the response model
  std::string profile = "maniskill";      ///< simulator fidelity profile of that calibration
  int episodes = 20;                      ///< episodes per repetition
  int steps = 50;                         ///< control steps per episode
  int repetitions = 5;                    ///< medians over repetitions
  std::uint64_t seed = 1;
  bool json = false;
};
int run_bench_adapt(const BenchAdaptOptions& o);

}  // namespace actionshift::cli
