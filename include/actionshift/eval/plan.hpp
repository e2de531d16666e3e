#pragma once
/// \file Experiment plans: an experiment YAML (`configs/experiments/<name>.yaml`) expands to the
/// cartesian product of its jobs, written as a JSON plan file and, for a cluster, a Slurm job array
/// script with one array task per job index (docs/formats.md "Experiment", "Plan file").

#include "actionshift/eval/job.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace actionshift::eval {

/// A method of an experiment with its parameters.
struct MethodEntry {
  MethodEntry() = default;
  /// A method and its parameters (an external method's rung, version and files keep their defaults).
  MethodEntry(std::string method_name, std::string method_params = "{}")
      : name(std::move(method_name)), params(std::move(method_params)) {}
  std::string name;             ///< method name, e.g. "oracle"
  std::string params{"{}"};     ///< canonical JSON object text of its parameters
  /// An external method's (`external:<command>`, docs/methods.md) declared rung, version and files
  /// (YAML keys rung, version, files; files relative to the experiment file's directory).
  std::string rung{"none"};
  std::string version{"0"};
  std::vector<std::string> files;
  bool operator==(const MethodEntry&) const = default;
};

/// An experiment as written in YAML. Keys: name, tasks, splits, methods, seeds, episodes, backbone
/// (required); pool (default null), rotation_mode (default "live"), profile (simulator fidelity,
/// default "maniskill"), description (free text).
struct Experiment {
  std::string source;                 ///< file it was read from (for messages)
  std::string source_sha256;          ///< SHA-256 of the file bytes
  std::string name;                   ///< experiment name
  std::string description;            ///< free text, not hashed into jobs
  std::vector<std::string> tasks;     ///< task names
  std::vector<std::string> splits;    ///< split names
  std::vector<MethodEntry> methods;   ///< methods with parameters
  std::vector<std::uint64_t> seeds;   ///< experimental seeds
  std::int64_t episodes{0};           ///< episodes per (task, split, method, seed) job
  std::string backbone;               ///< backbone name
  std::optional<std::string> pool;    ///< pool name, or none
  /// Per-split pools (YAML `pool: {split: pool, ...}`, every split named); overrides `pool`.
  std::map<std::string, std::optional<std::string>> split_pools;
  std::string rotation_mode{"live"};  ///< "live" or "identity"
  std::string profile{"maniskill"};   ///< simulator fidelity profile: "maniskill" or "ideal"
};

/// Parse experiment YAML text. `source` names it in errors.
/// Throws actionshift::InputError(source, field, reason) for malformed YAML (source gets `:line`),
/// an unknown or missing key, a wrong type, an empty or duplicated list entry.
Experiment parse_experiment(std::string_view yaml_text, const std::string& source);

/// Read and parse an experiment file (as parse_experiment; a missing file is an InputError).
Experiment load_experiment(const std::string& path);

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

/// Most jobs one plan may hold. The largest committed experiment (tournament.yaml) has 936; a plan
/// file costs about 1.2 KB per job, so 100,000 jobs are a 120 MB plan (an 80 KB experiment used to
/// expand to 180,000 jobs and a 220 MB plan). parse_experiment, make_plan and plan_from_json check it
/// from the list sizes, before any job is expanded or read.
inline constexpr std::uint64_t kMaxPlanJobs = 100000;

/// tasks × splits × methods × seeds of `ex`, saturating at UINT64_MAX.
std::uint64_t experiment_job_count(const Experiment& ex);

/// Expand an experiment into its jobs (stable order: tasks, then splits, methods, seeds, each in
/// file order). Throws actionshift::InputError from the resolver or for an invalid job, and (before
/// expanding) for more than kMaxPlanJobs jobs.
Plan make_plan(const Experiment& experiment, const PlanResolver& resolver);

/// Plan file object: {"schema_version","experiment","source","source_sha256","job_count","jobs":[{"index","job_id","spec"}]}.
nlohmann::json plan_to_json(const Plan& plan);

/// Inverse of plan_to_json. Each stored job_id is checked against its recomputed spec hash and each
/// index against its position. Throws actionshift::InputError(source, field, reason).
Plan plan_from_json(const nlohmann::json& j, const std::string& source);

/// Read a plan file (as plan_from_json).
Plan load_plan(const std::string& path);

/// Write a plan file atomically (indented JSON).
void write_plan(const std::string& path, const Plan& plan);

/// Slurm's default MaxArraySize: array indices must be below it.
inline constexpr unsigned kDefaultMaxArraySize = 1001;

/// Options of the Slurm scripts. Paths should be absolute (the CLI makes them so): the scripts run
/// from whatever directory Slurm starts them in.
struct SlurmOptions {
  std::string plan_path;                  ///< plan file the array tasks read
  std::string out_dir{"results"};         ///< results directory
  std::string executable{"actionshift"};  ///< CLI to call (absolute path)
  unsigned cpus_per_task{2};              ///< `--cpus-per-task`, also passed as `--threads`
  std::string time_limit{"02:00:00"};     ///< `--time` (validated by valid_slurm_time)
  std::string mem;                        ///< `--mem` (omitted when empty; validated by valid_slurm_mem)
  std::string partition;                  ///< `--partition` (omitted when empty)
  unsigned max_parallel{0};               ///< array throttle `%N` (0: none)
  unsigned max_array_size{kDefaultMaxArraySize};  ///< the cluster's MaxArraySize; chunks hold at most this many tasks
  std::string script_path;                ///< where the array script will be written (named by the submit script)
  std::string merge_script_path;          ///< where the merge script will be written (named by the submit script)
};

/// One array submission: plan jobs [offset, offset + count).
struct SlurmChunk {
  std::int64_t offset{0};
  std::int64_t count{0};
};

/// The plan's jobs split into consecutive chunks of at most max_array_size tasks (indices 0..count-1
/// within a chunk, so every index stays below MaxArraySize). Throws std::invalid_argument for
/// max_array_size == 0.
std::vector<SlurmChunk> slurm_chunks(std::int64_t job_count, unsigned max_array_size);

/// The sbatch script of one array task: runs plan job `ACTIONSHIFT_JOB_OFFSET + SLURM_ARRAY_TASK_ID`
/// with `actionshift run --plan PLAN --job-index I --out DIR --threads CPUS`. When the plan fits in one
/// chunk it also carries `#SBATCH --array=0-(N-1)`, so `sbatch <script>` alone works; the submit
/// script passes `--array` and the offset per chunk on the sbatch command line. Re-submitting is safe:
/// finished jobs are no-ops and killed ones resume. Throws std::invalid_argument for an empty plan.
std::string slurm_array_script(const Plan& plan, const SlurmOptions& options);

/// The sbatch script of the merge job: `actionshift summarize OUT` (Markdown and JSON beside the
/// results) and, when the plan holds both `oracle` and `no_adapt`, `actionshift gate1 --results OUT`.
std::string slurm_merge_script(const Plan& plan, const SlurmOptions& options);

/// A bash script that submits every chunk (`sbatch --parsable --array=0-(n-1) --export=ALL,
/// ACTIONSHIFT_JOB_OFFSET=o ARRAY_SCRIPT`) and then the merge script with
/// `--dependency=afterok:<every array job id>`; it prints the job ids.
std::string slurm_submit_script(const Plan& plan, const SlurmOptions& options);

/// True for Slurm `--time` formats: M, M:S, H:M:S, D-H, D-H:M, D-H:M:S (all digits, minutes and seconds
/// below 60, not all zero), or UNLIMITED / INFINITE.
bool valid_slurm_time(std::string_view text);

/// True for Slurm `--mem`: a positive integer with an optional K, M, G or T suffix (megabytes without).
bool valid_slurm_mem(std::string_view text);

/// MaxArraySize from the text of `scontrol show config` ("MaxArraySize = 1001"); nullopt if absent.
std::optional<unsigned> parse_max_array_size(std::string_view scontrol_config);

/// POSIX shell single-quoting of `s`.
std::string shell_quote(std::string_view s);

}  // namespace actionshift::eval
