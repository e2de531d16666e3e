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

int run_run(const RunCliOptions& o) {
  const EpisodeFnFactory factory = [](const eval::JobSpec& job) { return eval::make_episode_fn(job); };
  if (!o.run.plan_file.empty()) return run_plan_jobs(o.run, factory);
  try {
    eval::JobRequest q = o.request;
    q.method.params = o.method_params;
    const eval::JobSpec job = eval::resolve_job(q, eval::default_resolver());
    return run_one_job(job, o.run, factory);
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

int run_plan_cli(const PlanOptions& o) { return run_plan(o, eval::default_resolver()); }

int run_calibrate(const CalibrateOptions& o) {
  sim::EnvConfig cfg;
  try {
    cfg = sim::profile_config(o.profile);
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--profile", e.what());
  }
  std::string overrides;
  auto note = [&overrides](const std::string& k, const std::string& v) { overrides += (overrides.empty() ? "" : ",") + k + "=" + v; };
  if (!o.ik.empty()) {
    if (o.ik == "single_step") cfg.ik.mode = sim::IkMode::kSingleStep;
    else if (o.ik == "converged") cfg.ik.mode = sim::IkMode::kConverged;
    else throw InputError("", "--ik", "expected single_step or converged (got '" + o.ik + "')");
    note("ik", o.ik);
  }
  if (!o.drive.empty()) {
    if (o.drive == "implicit_pd") cfg.physics.arm_drive = sim::ArmDrive::kImplicitPd;
    else if (o.drive == "velocity_servo") cfg.physics.arm_drive = sim::ArmDrive::kVelocityServo;
    else throw InputError("", "--drive", "expected implicit_pd or velocity_servo (got '" + o.drive + "')");
    note("drive", o.drive);
  }
  if (o.solver_iterations != 0) {
    if (o.solver_iterations < 1 || o.solver_iterations > 1000) throw InputError("", "--solver-iterations", "must be in 1..1000");
    cfg.physics.solver_iterations = o.solver_iterations;
    note("solver_iterations", std::to_string(o.solver_iterations));
  }
  if (!o.joint_limits.empty()) {
    if (o.joint_limits != "on" && o.joint_limits != "off") throw InputError("", "--joint-limits", "expected on or off");
    cfg.physics.arm_joint_limits = o.joint_limits == "on";
    note("joint_limits", o.joint_limits);
  }
  if (!overrides.empty()) cfg.profile += "[" + overrides + "]";
  const auto model = sim::EnvModel::make(sim::parse_task(o.task), cfg);
  eval::CalibrationOptions co;
  try {
    co.protocol = eval::parse_protocol(o.protocol);
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--protocol", e.what());
  }
  co.episodes = o.episodes;
  co.steps = o.steps;
  co.seed = o.seed;
  co.gripper_channel = o.gripper_channel;
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
  double mean_r2 = 0.0;
  for (double r : c.fit.fit_r2) mean_r2 += r / 6.0;
  std::cout << "response calibration: " << c.task << " on profile " << c.profile << " (protocol " << c.protocol << ": "
            << c.episodes << (c.protocol == "reference_walk" ? " walks" : " episodes") << " x " << c.steps
            << " steps of uniform random actions, seed " << c.seed << ")\n"
            << "tcp_pose at observation offset " << c.slice.position_start << "\n\n"
            << "channel   alpha [per unit]   sigma      R^2\n";
  for (int k = 0; k < 6; ++k) {
    const auto i = static_cast<std::size_t>(k);
    std::cout << std::left << std::setw(10) << kChannels[k] << std::right << std::setw(12) << std::fixed
              << std::setprecision(5) << c.fit.alpha[i] << std::setw(16) << c.fit.sigma[i] << std::setw(9)
              << std::setprecision(3) << c.fit.fit_r2[i] << "\n";
  }
  std::cout << "mean R^2 over the six pose channels: " << std::setprecision(3) << mean_r2 << "\n";
  if (c.gripper)
    std::cout << std::left << std::setw(10) << "fingers" << std::right << std::setw(12) << std::setprecision(5)
              << c.gripper->alpha << std::setw(16) << c.gripper->sigma << std::setw(9) << std::setprecision(3)
              << c.gripper->fit_r2 << "   (finger block at observation offset " << c.gripper->start << ")\n";
  std::cout << "\ncalibration_sha256 " << c.sha256() << (o.out.empty() ? "" : "  written to " + o.out) << "\n";
  return kOk;
}

}  // namespace actionshift::cli
