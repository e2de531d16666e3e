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
