// env throughput: scripted contact-rich episodes on one or more threads
#include "actionshift/sim/bench.hpp"

#include "actionshift/core/workers.hpp"

#include "actionshift/core/rng.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/grasp_script.hpp"
#include "physics_world.hpp"

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

RawBulletLimit measure_raw_bullet(TaskId task, long long steps, std::uint64_t seed,
                                  std::shared_ptr<const RobotDescription> robot, std::string_view profile) {
  if (steps < 1) throw std::invalid_argument("steps must be >= 1 (got " + std::to_string(steps) + ")");
  using Clock = std::chrono::steady_clock;
  const auto model = EnvModel::make(task, profile_config(profile), std::move(robot));
  Env env(model);
  detail::BulletInputRecorder rec;
  struct Guard {
    explicit Guard(detail::BulletInputRecorder* r) { detail::set_thread_input_recorder(r); }
    ~Guard() { detail::set_thread_input_recorder(nullptr); }
    Guard(const Guard&) = delete;
    Guard& operator=(const Guard&) = delete;
  } guard(&rec);
  RawBulletLimit out;
  out.identical = true;
  std::uint64_t episode = 0;
  while (out.steps < steps) {
    const std::uint64_t s = derive_seed({seed, episode++});
    // the controlled episode, inputs recorded
    rec.recording = true;
    rec.inputs.clear();
    env.reset(s);
    detail::PhysicsWorld* world = rec.world;
    if (world == nullptr) throw std::logic_error("raw bullet: the environment's world was not seen");
    GraspLiftScript script;
    long long n = 0;
    Clock::duration in_step{};
    while (!env.last().episode_over() && out.steps + n < steps) {
      const Action a = script.act(env.snapshot());
      const auto t0 = Clock::now();
      env.step(a);
      in_step += Clock::now() - t0;
      ++n;
    }
    const Eigen::Matrix<double, 9, 1> q_end = env.qpos();
    const TaskSnapshot end = env.snapshot();
    // the same world rebuilt from the same seed, stepped with the recorded inputs only
    rec.recording = false;
    env.reset(s);
    if (rec.world != world) throw std::logic_error("raw bullet: the world changed between the runs");
    const int stride = world->inputs_per_control_step();
    if (rec.inputs.size() != static_cast<std::size_t>(n) * static_cast<std::size_t>(stride))
      throw std::logic_error("raw bullet: recorded inputs do not match the steps taken");
    const auto t0 = Clock::now();
    for (long long k = 0; k < n; ++k) world->replay_control(rec.inputs.data() + k * stride);
    out.raw_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    out.env_seconds += std::chrono::duration<double>(in_step).count();
    const TaskSnapshot replayed = env.snapshot();
    bool same = env.qpos() == q_end && replayed.qvel == end.qvel;
    for (std::size_t o = 0; o < 2; ++o)
      same = same && replayed.obj[o].matrix() == end.obj[o].matrix() && replayed.obj_linvel[o] == end.obj_linvel[o];
    out.identical = out.identical && same;
    out.steps += n;
    ++out.episodes;
  }
  out.ratio = out.env_seconds > 0 ? out.raw_seconds / out.env_seconds : 0.0;
  return out;
}

}  // namespace actionshift::sim
