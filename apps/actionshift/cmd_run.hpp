#pragma once
// `actionshift run` (single job or plan) and `actionshift calibrate`: plain functions binding the
// eval layer's runner to the real episode function (eval/episode_fn.hpp). No CLI11 here.

#include "cmd_eval.hpp"
#include "commands.hpp"

#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/sim/robot_source.hpp"

#include <cstdint>
#include <optional>
#include <string>

namespace actionshift::cli {

// `actionshift run --task T --split S --method M --seed X [--episodes N] [--backbone B] [--pool P]
//  [--params JSON] [--rotation-mode live|identity] --out DIR`  or  `actionshift run --plan FILE
//  [--job-index I] --out DIR`; both with [--threads N] [--fsync] [--progress MODE].
// The options that name one job, shared by `run` and `render` (which must reach the same job id).
struct CliJobOptions {
  eval::JobRequest request;        // --task --split --method --seed --episodes --backbone --pool ...
  std::string method_params{"{}"}; // --params: JSON object of method parameters
  RobotOptions robot;              // --robot/--package (single job; a plan carries its own)
  std::vector<std::string> policy_files;  // --policy-files: files of an external policy (content hashed into the id)
  std::string calibration;         // --calibration: response calibration file instead of the built-in one
  std::string seed_file;           // --seed-file: the experimental seed read from a file (an evaluator's undisclosed seed)
  // --method external:<command>: its declared rung, version and files (docs/methods.md)
  std::string method_rung{"none"};
  std::string method_version{"0"};
  std::vector<std::string> method_files;
};
// The job these options name, and the run-time options of its episode function (the calibration
// file, read and checked against the job's task and profile). Throws actionshift::InputError.
void resolve_cli_job(const CliJobOptions& o, eval::JobSpec& job, eval::EpisodeFnOptions& options);

struct RunCliOptions {
  CliJobOptions job;               // single job (ignored with --plan)
  RunPlanOptions run;              // plan_file, job_index, out_dir, threads, fsync, progress
};
int run_run(const RunCliOptions& o);

// `actionshift plan --experiment FILE ...` with the real resolver; --robot/--package go into every job.
int run_plan_cli(const PlanOptions& o, const RobotOptions& robot, const std::vector<std::string>& policy_files);

// The PolicyFilesRef of --policy-files (nullopt when none); `backbone` must be external:<command>.
std::optional<eval::PolicyFilesRef> cli_policy_files(const std::vector<std::string>& files, const std::string& backbone);

// The robot of --robot/--package: nullopt for the embedded Panda. Throws actionshift::InputError.
std::optional<sim::RobotSource> load_cli_robot(const RobotOptions& o);
// The same as a job's RobotRef.
std::optional<eval::RobotRef> cli_robot_ref(const RobotOptions& o);

// `actionshift calibrate --task T [--episodes N] [--steps N] [--seed S] [--out FILE] [--json]`
struct CalibrateOptions {
  /// Bound directly: --episodes, --steps, --seed, --gripper-channel (checked by eval::calibrate);
  /// `protocol` is set from the option below.
  eval::CalibrationOptions calibration;
  std::string task;
  std::string profile{"maniskill"};
  std::string protocol{"maniskill_walk"};
  // ablation overrides of the profile ("" = the profile's own setting); the calibration's profile
  // label then names them, e.g. "maniskill[ik=converged]"
  std::string ik;                    // single_step | converged
  std::string drive;                 // implicit_pd | velocity_servo
  std::optional<int> solver_iterations;  // set: Bullet solver iterations (1..1000)
  std::string joint_limits;          // on | off: arm joint limit constraints
  std::string out;   // write the calibration JSON here ("" → print it only)
  bool json{false};  // print the calibration JSON instead of the table
  RobotOptions robot;  // --robot/--package
  double obs_noise{0.0};        // --obs-noise: observation-noise sigma (label "[obs_noise=S]" on the profile)
};
int run_calibrate(const CalibrateOptions& o);

}  // namespace actionshift::cli
