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

/// The raw-Bullet limit of the same world: `steps` control steps of scripted grasp-and-lift episodes
/// (one thread) are timed through Env::step while the inputs the controller hands Bullet are recorded;
/// each episode is then rebuilt from its seed and the same bodies are stepped with those inputs and
/// no controller work (no IK, implicit-PD solve, observation, contact forces or checks).
struct RawBulletLimit {
  long long steps{0};            ///< control steps in both runs
  int episodes{0};               ///< episodes (each replayed once)
  double env_seconds{0.0};       ///< time inside Env::step (the script's actions are outside)
  double raw_seconds{0.0};       ///< time stepping Bullet with the recorded inputs
  double ratio{0.0};             ///< raw_seconds / env_seconds: the share of Env::step that is Bullet
  bool identical{false};         ///< every replayed episode ended in the recorded joint state, bit for bit
};
RawBulletLimit measure_raw_bullet(TaskId task, long long steps, std::uint64_t seed = 1,
                                  std::shared_ptr<const RobotDescription> robot = nullptr,
                                  std::string_view profile = "maniskill");

}  // namespace actionshift::sim
