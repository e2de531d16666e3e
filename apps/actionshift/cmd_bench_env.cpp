// actionshift bench env: control steps per second of the Bullet environment, one thread and all threads
#include "commands.hpp"

#include "actionshift/sim/bench.hpp"
#include "actionshift/sim/robot_source.hpp"

#include <cstdio>
#include <thread>

namespace actionshift::cli {

int run_bench_env(const BenchEnvOptions& o) {
  const sim::TaskId task = sim::parse_task(o.task);
  const int threads = o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (o.steps < 1) {
    std::fprintf(stderr, "actionshift: error: --steps: must be >= 1 (got %lld)\n", o.steps);
    return kBadInput;
  }
  if (o.robot.urdf.empty() && !o.robot.packages.empty()) {
    std::fprintf(stderr, "actionshift: error: --package: %s: needs --robot URDF\n", o.robot.packages.front().c_str());
    return kBadInput;
  }
  std::shared_ptr<const sim::RobotDescription> robot;
  if (!o.robot.urdf.empty()) robot = sim::load_robot_source(o.robot.urdf, sim::parse_package_args(o.robot.packages)).description;
  if (o.raw_bullet) {
    const sim::RawBulletLimit r = sim::measure_raw_bullet(task, o.steps, 1, robot, o.profile);
    const double env_us = 1e6 * r.env_seconds / static_cast<double>(r.steps);
    const double raw_us = 1e6 * r.raw_seconds / static_cast<double>(r.steps);
    if (o.json) {
      std::printf("{\"task\":\"%s\",\"profile\":\"%s\",\"steps\":%lld,\"episodes\":%d,\"env_us_per_step\":%.2f,"
                  "\"raw_us_per_step\":%.2f,\"raw_share\":%.4f,\"identical\":%s}\n",
                  std::string(sim::task_name(task)).c_str(), o.profile.c_str(), r.steps, r.episodes, env_us, raw_us, r.ratio,
                  r.identical ? "true" : "false");
    } else {
      std::printf("task %s: scripted grasp-and-lift, %lld control steps (%d episodes), one thread\n",
                  std::string(sim::task_name(task)).c_str(), r.steps, r.episodes);
      std::printf("  Env::step                          : %8.1f us per control step\n", env_us);
      std::printf("  raw Bullet (same world, no control): %8.1f us per control step (%.1f %% of Env::step)\n", raw_us,
                  100.0 * r.ratio);
      std::printf("  replay bit-identical               : %s\n", r.identical ? "yes" : "NO");
    }
    return r.identical ? kOk : kCheckFailed;
  }
  const sim::EnvThroughput one = sim::measure_env_throughput(task, o.steps, 1, 1, robot, o.profile);
  const sim::EnvThroughput all = sim::measure_env_throughput(task, o.steps, threads, 1, robot, o.profile);
  if (o.json) {
    std::printf("{\"task\":\"%s\",\"profile\":\"%s\",\"threads\":%d,\"steps_per_s_one_thread\":%.1f,\"steps_per_s_all_threads\":%.1f}\n",
                std::string(sim::task_name(task)).c_str(), o.profile.c_str(), threads, one.steps_per_s, all.steps_per_s);
  } else {
    std::printf("task %s: scripted grasp-and-lift episodes (contact), %lld control steps per thread\n",
                std::string(sim::task_name(task)).c_str(), o.steps);
    std::printf("  1 thread : %10.1f control steps/s\n", one.steps_per_s);
    std::printf("  %d threads: %10.1f control steps/s (%.2fx)\n", threads, all.steps_per_s,
                one.steps_per_s > 0 ? all.steps_per_s / one.steps_per_s : 0.0);
  }
  return kOk;
}

}  // namespace actionshift::cli
