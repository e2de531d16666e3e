#pragma once
// Evaluation subcommands of the actionshift CLI as plain functions (no CLI11 here): cli_eval.cpp binds
// the parsed options into these structs. Each returns an exit status: 0 ok, 1 check failed, 2 bad input
// (after printing one line `actionshift: error: ...` to `err`).

#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/runner.hpp"

#include <cstdint>
#include <functional>
#include <iostream>
#include <optional>
#include <string>

namespace actionshift::cli {

// `actionshift summarize DIR [--json] [--out FILE]`
struct SummarizeOptions {
  std::string results_dir;   // DIR (positional)
  bool json{false};          // --json: print JSON instead of Markdown
  std::string out_file;      // --out FILE: also write the JSON summary there (atomic)
};
int run_summarize(const SummarizeOptions& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift gate1 --results DIR [--json] [--verdict FILE] [--samples N] [--bootstrap-seed S]`
// Prints the Gate 1 table (or JSON), writes the verdict file (default DIR/gate1.verdict.json);
// exit 1 when a gated cell is not "pass".
struct Gate1Options {
  std::string results_dir;                          // --results DIR
  bool json{false};                                 // --json
  std::string verdict_file;                         // --verdict FILE ("" → <results>/gate1.verdict.json)
  std::size_t samples{10000};                       // --samples N (bootstrap resamples)
  std::uint64_t bootstrap_seed{20260718};           // --bootstrap-seed S
};
int run_gate1(const Gate1Options& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift gate check --expected FILE (--results DIR | --actual FILE)`
// Recomputes the verdicts of the expected file's gate from DIR (gate1), or reads them from FILE
// (any gate), prints one line per cell, exits 1 if an expected "pass" is now anything else.
struct GateCheckOptions {
  std::string expected_file;   // --expected FILE (committed verdicts)
  std::string results_dir;     // --results DIR (recompute; gate1 verdict files)
  std::string actual_file;     // --actual FILE (compare two verdict files instead)
};
int run_gate_check(const GateCheckOptions& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift gate promote --candidate M --baseline M' --results DIR [--json] [--verdict FILE]`
// Applies the promotion rules (docs/reference.md, *Gates*) per (task, split) cell holding both methods; prints the
// table with its evidence and writes the verdict file (default DIR/promotion.<M>.vs.<M'>.json).
// Exit 0 (the verdicts are the output; `gate check` turns a lost promotion into exit 1).
struct GatePromoteOptions {
  std::string candidate;        // --candidate M
  std::string baseline;         // --baseline M'
  std::string results_dir;      // --results DIR
  bool json{false};             // --json
  std::string verdict_file;     // --verdict FILE
};
int run_gate_promote(const GatePromoteOptions& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift plan --experiment FILE [--out DIR] [--plan FILE] [--slurm] [--slurm-script FILE]
//  [--executable PATH] [--cpus-per-task N] [--time HH:MM:SS] [--partition P] [--max-parallel N]`
// Writes the plan (default <out>/<experiment>.plan.json) and, with --slurm, an sbatch array script
// (default <out>/<experiment>.sbatch). Paths in the script are absolute.
struct PlanOptions {
  std::string experiment_file;          // --experiment FILE
  std::string out_dir{"results"};       // --out DIR (results directory of the array tasks)
  std::string plan_file;                // --plan FILE ("" → <out>/<experiment>.plan.json)
  bool slurm{false};                    // --slurm
  std::string slurm_file;               // --slurm-script FILE ("" → <out>/<experiment>.sbatch)
  std::string executable;               // --executable PATH ("" → this binary, /proc/self/exe); made absolute
  unsigned cpus_per_task{2};            // --cpus-per-task N
  std::string time_limit{"02:00:00"};   // --time (Slurm time format, validated)
  std::string mem;                      // --mem (Slurm memory, e.g. 4G; "" → not set)
  std::string partition;                // --partition
  unsigned max_parallel{0};             // --max-parallel N (array throttle)
  std::optional<unsigned> max_array_size;  // --max-array-size N (unset: `scontrol show config`, else 1001)
  std::optional<eval::RobotRef> robot;  // set by the caller from --robot/--package: every job runs with it
  std::optional<eval::PolicyFilesRef> policy_files;  // set by the caller from --policy-files: every job names them
};
// The absolute path of `executable` ("" → the running binary): a name without '/' is looked up on
// PATH. Throws InputError when it is not an executable file.
std::string resolve_executable(const std::string& executable);
// MaxArraySize from `scontrol show config` when scontrol runs, else eval::kDefaultMaxArraySize.
unsigned cluster_max_array_size();
int run_plan(const PlanOptions& options, const eval::PlanResolver& resolver, std::ostream& out = std::cout,
             std::ostream& err = std::cerr);

// Builds the episode function of a job (the sim/policy/adapter layers); throws actionshift::InputError
// for an unknown method or backbone.
using EpisodeFnFactory = std::function<eval::EpisodeFn(const eval::JobSpec& job)>;

// `actionshift run --plan FILE [--job-index I] --out DIR [--threads N] [--fsync] [--progress MODE]`
// Runs job I of the plan, or every job in order when no index is given. Finished jobs are no-ops.
struct RunPlanOptions {
  std::string plan_file;                    // --plan FILE
  std::optional<std::int64_t> job_index;    // --job-index I
  std::string out_dir{"results"};           // --out DIR
  unsigned threads{0};                      // --threads N (0: all cores)
  bool fsync{false};                        // --fsync
  std::string progress{"auto"};             // --progress auto|bar|lines|off
  double step_timeout_s{10.0};              // --step-timeout S: external policy request/reply bound
  std::string sandbox{"auto"};              // --sandbox auto|on|off: external processes' sandbox
  std::vector<std::string> hidden_paths;    // hidden from them besides --out and --plan (the seed file)
};
int run_plan_jobs(const RunPlanOptions& options, const EpisodeFnFactory& make_episode_fn,
                  std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift run --task T --split S --method M --seed X ...`: one job already resolved into a spec
// by cmd_run.cpp (with the same resolver as `plan`), run with the options of RunPlanOptions
// (plan_file and job_index are ignored).
int run_one_job(const eval::JobSpec& job, const RunPlanOptions& options, const EpisodeFnFactory& make_episode_fn,
                std::ostream& out = std::cout, std::ostream& err = std::cerr);

// Output paths are checked before any work starts. A file path (`--out FILE`, `--verdict FILE`) must
// not be an existing directory, end in '/', or sit below an existing non-directory; a directory path
// (`--out DIR` of run) must not be an existing non-directory, nor sit below one, and must be writable
// when it exists. throws actionshift::InputError(path, option, reason).
void check_output_file(const std::string& path, const std::string& option);
void check_output_dir(const std::string& path, const std::string& option);

// "auto"|"bar"|"lines"|"off" → ProgressMode; throws actionshift::InputError otherwise.
eval::ProgressMode parse_progress_mode(const std::string& text);

}  // namespace actionshift::cli
