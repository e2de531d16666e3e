#pragma once
/// \file Plan expansion: an Experiment (experiment_yaml.hpp) expands to the cartesian product of its
/// jobs, each name resolved to a hashed reference by a PlanResolver (eval/resolve.hpp has the one the
/// CLI uses); a single job from the command line resolves through the same resolver. The plan file
/// is plan_io.hpp, the Slurm scripts slurm.hpp.

#include "actionshift/eval/experiment_yaml.hpp"
#include "actionshift/eval/job.hpp"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::eval {

/// Resolves names to hashed references when a plan is made. Each function throws
/// actionshift::InputError for an unknown name. `pool` is only called when the experiment names a
/// pool; empty `calibration` means no calibration hash; empty `check_method` accepts every method.
struct PlanResolver {
  std::function<SplitRef(const std::string& task, const std::string& split)> split;
  std::function<BackboneRef(const std::string& task, const std::string& backbone)> backbone;
  std::function<PoolRef(const std::string& pool)> pool;
  std::function<std::optional<std::string>(const std::string& task, const MethodEntry& method, const std::string& profile)>
      calibration;
  /// If set: the method as written (a label such as `entropy_probes{calibrated}` with its params) in
  /// the form every other callback receives: the base name and the label's parameters merged with the
  /// entry's. Unset: the entry as written.
  std::function<MethodEntry(const MethodEntry& method)> canonical_method;
  std::function<void(const MethodEntry& method)> check_method;
  /// If set: the method's parameters as they enter the job spec (e.g. with defaults filled in, so
  /// a changed default changes the job id). Unset: the parameters as written.
  std::function<std::string(const MethodEntry& method)> method_params;
  /// If set: whether a method takes the experiment's pool (false: its jobs get no pool, so e.g. an
  /// oracle job has the same id with or without a pool in the experiment). Unset: every method does.
  std::function<bool(const MethodEntry& method)> method_uses_pool;
  /// If set: the identity of a registered user method (adapt::register_method), nullopt for a
  /// built-in. Unset: every method is a built-in.
  std::function<std::optional<MethodPluginRef>(const MethodEntry& method)> method_plugin;
};

/// A single job by names, as on the `actionshift run --task T --split S --method M ...` command line.
struct JobRequest {
  std::string task;                   ///< task name
  std::string split;                  ///< split name
  MethodEntry method;                 ///< method and parameters
  std::string backbone{"expert"};     ///< backbone name
  std::optional<std::string> pool;    ///< pool name, or none
  std::string rotation_mode{"live"};  ///< "live" or "identity"
  std::string profile{"maniskill"};   ///< simulator fidelity profile
  std::uint64_t seed{20260718};       ///< experimental seed
  std::int64_t episodes{256};         ///< episodes
  double obs_noise{0.0};              ///< observation-noise sigma (run/render --obs-noise; 0 = off)
  int horizon{0};                     ///< control steps per episode (run/render --horizon; 0 = the task's)
  std::string source{"command line"};  ///< where the request came from, named in its errors
};

/// Resolve a request into a validated JobSpec with the same resolver `plan` uses, so a job run from
/// the command line has the same id as the same job run from a plan.
/// Throws actionshift::InputError from the resolver or for an invalid field (named by `request.source`).
JobSpec resolve_job(const JobRequest& request, const PlanResolver& resolver);

/// One job of a plan.
struct PlannedJob {
  std::int64_t index{0};   ///< position in the plan (the Slurm array task id)
  std::string job_id;      ///< job_id(spec)
  JobSpec spec;            ///< the job
};

/// A materialised experiment.
struct Plan {
  std::string experiment;       ///< experiment name
  std::string source;           ///< experiment file
  std::string source_sha256;    ///< its SHA-256
  std::vector<PlannedJob> jobs; ///< tasks × splits × methods × seeds, nested in that order (seed innermost)
};

/// Expand an experiment into its jobs (stable order: tasks, then splits, methods, seeds, each in
/// file order). Throws actionshift::InputError from the resolver or for an invalid job, and (before
/// expanding) for more than kMaxPlanJobs jobs.
Plan make_plan(const Experiment& experiment, const PlanResolver& resolver);

}  // namespace actionshift::eval
