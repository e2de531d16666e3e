// run, plan (with the real resolver) and calibrate.
#include "cmd_run.hpp"

#include "actionshift/adapt/plugin.hpp"
#include "actionshift/eval/external_method.hpp"

#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/sim/task.hpp"
#include "commands.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

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

namespace {

// --obs-noise: a finite sigma in [0, 0.1] (metres / radians), else a one-line InputError
void check_obs_noise(double sigma) {
  if (!(sigma >= 0.0 && sigma <= sim::kMaxObsNoise)) {  // also rejects NaN
    std::ostringstream got;
    got << sigma;
    throw InputError("command line", "--obs-noise", "must be a finite sigma in [0, 0.1] (metres / radians; got " + got.str() + ")");
  }
}

}  // namespace

// --seed-file: one decimal integer in [0, 2**64), surrounding whitespace allowed. The seed stays out of
// the command line, which every process of the machine (an external policy too) can read.
std::uint64_t read_seed_file(const std::string& path) {
  const std::string text = read_input_file(path, "seed file", 4096);
  const auto a = text.find_first_not_of(" \t\r\n");
  const auto b = text.find_last_not_of(" \t\r\n");
  const std::string s = a == std::string::npos ? std::string() : text.substr(a, b - a + 1);
  const bool digits = !s.empty() && s.size() <= 20 && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits || (s.size() == 20 && s > "18446744073709551615"))
    throw InputError(path, "seed", "must hold one integer in [0, 2**64) (got " + quote_input(s) + ")");
  return std::stoull(s);
}

namespace {
// user methods registered by this command (external:<command>): they live as long as the process
std::vector<adapt::MethodRegistration>& registrations() {
  static std::vector<adapt::MethodRegistration> r;
  return r;
}
}  // namespace

void resolve_cli_job(const CliJobOptions& o, eval::JobSpec& job, eval::EpisodeFnOptions& options) {
  check_obs_noise(o.request.obs_noise);
  if (o.request.method.name.starts_with("external:")) {
    if (!adapt::find_method_plugin(o.request.method.name))
      registrations().push_back(eval::register_external_method(o.request.method.name.substr(9),
                                                               adapt::parse_rung(o.method_rung, "command line", "--method-rung"),
                                                               o.method_files, o.method_version, options.external));
  } else if (o.method_rung != "none" || o.method_version != "0" || !o.method_files.empty()) {
    throw InputError("command line", "--method-rung/--method-version/--method-files", "apply to --method external:<command> only");
  }
  // syntax errors and repeated keys of --params are named as the option's (the resolver parses it again)
  (void)parse_json_input(o.method_params, "command line", "--params");
  eval::JobRequest q = o.request;
  q.method.params = o.method_params;
  if (!o.seed_file.empty()) q.seed = read_seed_file(o.seed_file);
  job = eval::resolve_job(q, eval::default_resolver());
  job.robot = cli_robot_ref(o.robot);
  job.policy_files = cli_policy_files(o.policy_files, job.backbone.name);
  if (!o.calibration.empty()) {
    if (!job.calibration_sha256)
      throw InputError("command line", "--calibration", "method " + job.method + " uses no response calibration");
    adapt::ResponseCalibration cal = adapt::ResponseCalibration::load_for(o.calibration, job.task, "the job's " + job.task,
                                                                          job.profile, "the job's profile " + job.profile);
    job.calibration_sha256 = cal.sha256();
    options.calibration = std::move(cal);
    options.calibration_source = o.calibration;
  }
}

int run_run(const RunCliOptions& o) {
  eval::EpisodeFnOptions options;
  RunPlanOptions run = o.run;
  if (!o.job.seed_file.empty()) run.hidden_paths.push_back(o.job.seed_file);
  options.external.step_timeout_s = o.run.step_timeout_s;
  if (!o.run.plan_file.empty()) {
    const EpisodeFnFactory factory = [options](const eval::JobSpec& job) {
      // a plan's external method is registered from its own job spec (command, rung, version, files)
      registrations().push_back(eval::register_external_method_of(job, options.external));
      return eval::make_episode_fn(job, options);
    };
    if (!o.job.robot.urdf.empty() || !o.job.robot.packages.empty() || !o.job.policy_files.empty() || !o.job.calibration.empty() ||
        o.job.request.obs_noise != 0.0) {
      std::cerr << "actionshift: error: --plan: " << o.run.plan_file
                << ": a plan's jobs carry their robot and policy files (give --robot/--policy-files to `actionshift plan`);"
                   " --calibration and --obs-noise apply to a single job only\n";
      return kBadInput;
    }
    return run_plan_jobs(run, factory);
  }
  try {
    eval::JobSpec job;
    resolve_cli_job(o.job, job, options);
    const EpisodeFnFactory factory = [options](const eval::JobSpec& j) { return eval::make_episode_fn(j, options); };
    return run_one_job(job, run, factory);
  } catch (const eval::Interrupted&) {
    throw;  // not an error: main says where the job stopped (exit 130)
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
  if (!o.out.empty()) check_output_file(o.out, "--out");  // before the minutes of work, not after
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
  if (o.solver_iterations) {
    const int it = *o.solver_iterations;
    if (it < 1 || it > 1000) throw InputError("", "--solver-iterations", "must be in 1..1000 (got " + std::to_string(it) + ")");
    cfg.physics.solver_iterations = it;
    note("solver_iterations", std::to_string(it));
  }
  if (!o.joint_limits.empty()) {
    if (o.joint_limits != "on" && o.joint_limits != "off") throw InputError("", "--joint-limits", "expected on or off");
    cfg.physics.arm_joint_limits = o.joint_limits == "on";
    note("joint_limits", o.joint_limits);
  }
  check_obs_noise(o.obs_noise);
  if (o.obs_noise != 0.0) {
    std::ostringstream s;
    s << o.obs_noise;
    note("obs_noise", s.str());
    cfg.obs_noise = o.obs_noise;
  }
  if (!overrides.empty()) cfg.profile += "[" + overrides + "]";
  const auto robot = load_cli_robot(o.robot);
  const auto model = sim::EnvModel::make(sim::parse_task(o.task), cfg, robot ? robot->description : nullptr);
  eval::CalibrationOptions co = o.calibration;
  try {
    co.protocol = eval::parse_protocol(o.protocol);
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--protocol", e.what());
  }
  const adapt::ResponseCalibration c = eval::calibrate(model, co);
  if (!o.out.empty()) {
    const std::filesystem::path p(o.out);
    std::error_code ec;
    if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
    if (ec) throw InputError(o.out, "--out", "cannot create the parent directory: " + ec.message());
    write_file_atomic(o.out, c.to_json() + "\n");
  }
  if (o.json) {
    std::cout << c.to_json() << "\n";
    return kOk;
  }
  static const char* kChannels[6] = {"dx", "dy", "dz", "rx", "ry", "rz"};
  double mean_r2 = 0.0;
  for (double r : c.fit.fit_r2) mean_r2 += r / 6.0;
  std::cout << "response calibration: " << c.task << " on profile " << c.profile << " (protocol " << c.protocol << ": "
            << c.episodes << (c.protocol == "episodes" ? " episodes" : " walks") << " x " << c.steps
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
