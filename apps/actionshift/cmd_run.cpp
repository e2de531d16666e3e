// run, plan (with the real resolver) and calibrate.
#include "cmd_run.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/experiment.hpp"
#include "actionshift/sim/task.hpp"
#include "commands.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

namespace actionshift::cli {

std::optional<sim::RobotSource> load_cli_robot(const RobotOptions& o) {
  if (o.urdf.empty()) {
    if (!o.packages.empty()) throw InputError("--package", o.packages.front(), "needs --robot URDF");
    return std::nullopt;
  }
  return sim::load_robot_source(o.urdf, sim::parse_package_args(o.packages));
}

std::optional<eval::RobotRef> cli_robot_ref(const RobotOptions& o) {
  const auto r = load_cli_robot(o);
  if (!r) return std::nullopt;
  return eval::RobotRef{r->sha256, r->urdf, r->packages};
}

std::optional<eval::PolicyFilesRef> cli_policy_files(const std::vector<std::string>& files, const std::string& backbone) {
  if (files.empty()) return std::nullopt;
  if (!backbone.starts_with("external:"))
    throw InputError("--policy-files", files.front(), "only applies to an external:<command> backbone (got \"" + backbone + "\")");
  eval::PolicyFilesRef ref;
  ref.sha256 = eval::files_content_sha256(files);
  std::error_code ec;
  for (const auto& f : files) ref.paths.push_back(std::filesystem::absolute(f, ec).lexically_normal().string());
  return ref;
}

int run_run(const RunCliOptions& o) {
  const EpisodeFnFactory factory = [](const eval::JobSpec& job) { return eval::make_episode_fn(job); };
  if (!o.run.plan_file.empty()) {
    if (!o.robot.urdf.empty() || !o.robot.packages.empty() || !o.policy_files.empty()) {
      std::cerr << "actionshift: error: --plan: " << o.run.plan_file
                << ": a plan's jobs carry their robot and policy files; give --robot/--policy-files to `actionshift plan`\n";
      return kBadInput;
    }
    return run_plan_jobs(o.run, factory);
  }
  try {
    eval::JobRequest q = o.request;
    q.method.params = o.method_params;
    eval::JobSpec job = eval::resolve_job(q, eval::default_resolver());
    job.robot = cli_robot_ref(o.robot);
    job.policy_files = cli_policy_files(o.policy_files, job.backbone.name);
    return run_one_job(job, o.run, factory);
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

int run_plan_cli(const PlanOptions& o, const RobotOptions& robot, const std::vector<std::string>& policy_files) {
  try {
    PlanOptions with_robot = o;
    with_robot.robot = cli_robot_ref(robot);
    if (!policy_files.empty()) with_robot.policy_files = cli_policy_files(policy_files, "external:");
    return run_plan(with_robot, eval::default_resolver());
  } catch (const std::invalid_argument& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

int run_calibrate(const CalibrateOptions& o) {
  const auto robot = load_cli_robot(o.robot);
  const auto model = sim::EnvModel::make(sim::parse_task(o.task), {}, robot ? robot->description : nullptr);
  eval::CalibrationOptions co;
  co.episodes = o.episodes;
  co.steps = o.steps;
  co.seed = o.seed;
  const adapt::ResponseCalibration c = eval::calibrate(model, co);
  if (!o.out.empty()) {
    const std::filesystem::path p(o.out);
    if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
    const std::string tmp = o.out + ".tmp";
    {
      std::ofstream f(tmp, std::ios::binary);
      f << c.to_json() << "\n";
      if (!f) throw InputError(tmp, "", "cannot write file");
    }
    std::filesystem::rename(tmp, o.out);
  }
  if (o.json) {
    std::cout << c.to_json() << "\n";
    return kOk;
  }
  static const char* kChannels[6] = {"dx", "dy", "dz", "rx", "ry", "rz"};
  std::cout << "response calibration: " << c.task << " (" << c.episodes << " episodes x " << c.steps
            << " steps of uniform random actions, seed " << c.seed << ")\n"
            << "tcp_pose at observation offset " << c.slice.position_start << "\n\n"
            << "channel   alpha [per unit]   sigma      R^2\n";
  for (int k = 0; k < 6; ++k) {
    const auto i = static_cast<std::size_t>(k);
    std::cout << std::left << std::setw(10) << kChannels[k] << std::right << std::setw(12) << std::fixed
              << std::setprecision(5) << c.fit.alpha[i] << std::setw(16) << c.fit.sigma[i] << std::setw(9)
              << std::setprecision(3) << c.fit.fit_r2[i] << "\n";
  }
  std::cout << "\ncalibration_sha256 " << c.sha256() << (o.out.empty() ? "" : "  written to " + o.out) << "\n";
  return kOk;
}

}  // namespace actionshift::cli
