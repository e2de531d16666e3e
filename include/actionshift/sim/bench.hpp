#pragma once
/// \file
/// Throughput measurement of the environment (used by `actionshift bench env` and env_bench.cpp):
/// full-horizon episodes of the scripted grasp-and-lift, so every measurement includes contact.

#include "actionshift/sim/robot_description.hpp"
#include "actionshift/sim/task.hpp"

#include <cstdint>
#include <string_view>
#include <memory>

namespace actionshift::sim {

struct EnvThroughput {
  long long steps{0};           ///< control steps taken (all threads)
  double seconds{0.0};          ///< wall time
  double steps_per_s{0.0};      ///< steps / seconds (aggregate over threads)
};

/// Run `steps_per_thread` control steps on each of `threads` threads (one Env each, shared model),
/// episodes of the scripted grasp-and-lift seeded from `seed`; resets are included in the time.
/// `robot`: the description to simulate (nullptr: the embedded Panda); `profile`: the fidelity profile.
EnvThroughput measure_env_throughput(TaskId task, long long steps_per_thread, int threads, std::uint64_t seed = 1,
                                     std::shared_ptr<const RobotDescription> robot = nullptr,
                                     std::string_view profile = "maniskill");

}  // namespace actionshift::sim
