// env throughput: scripted contact-rich episodes on one or more threads
#include "actionshift/sim/bench.hpp"

#include "actionshift/core/workers.hpp"

#include "actionshift/core/rng.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/grasp_script.hpp"

#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

namespace actionshift::sim {
namespace {

long long run_episodes(const std::shared_ptr<const EnvModel>& model, long long steps, std::uint64_t seed) {
  Env env(model);
  long long done = 0;
  std::uint64_t episode = 0;
  while (done < steps) {
    env.reset(derive_seed({seed, episode++}));
    GraspLiftScript script;
    while (!env.last().episode_over() && done < steps) {
      env.step(script.act(env.snapshot()));
      ++done;
    }
  }
  return done;
}

}  // namespace

EnvThroughput measure_env_throughput(TaskId task, long long steps_per_thread, int threads, std::uint64_t seed,
                                     std::shared_ptr<const RobotDescription> robot, std::string_view profile) {
  if (threads < 1) throw std::invalid_argument("threads must be >= 1 (got " + std::to_string(threads) + ")");
  if (steps_per_thread < 1) throw std::invalid_argument("steps must be >= 1 (got " + std::to_string(steps_per_thread) + ")");
  const auto model = EnvModel::make(task, profile_config(profile), std::move(robot));
  std::vector<long long> done(static_cast<std::size_t>(threads), 0);
  const auto t0 = std::chrono::steady_clock::now();
  if (threads == 1) {
    done[0] = run_episodes(model, steps_per_thread, seed);
  } else {
    run_workers(static_cast<unsigned>(threads), [&](unsigned t) {
      done[t] = run_episodes(model, steps_per_thread, derive_seed({seed, 1000u + static_cast<std::uint64_t>(t)}));
    });
  }
  EnvThroughput r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (long long d : done) r.steps += d;
  r.steps_per_s = r.seconds > 0 ? static_cast<double>(r.steps) / r.seconds : 0.0;
  return r;
}

}  // namespace actionshift::sim
