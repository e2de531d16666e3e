#pragma once
/// \file Slurm scripts of a plan: a job array with one array task per plan job (in chunks under the
/// cluster's MaxArraySize), the merge job and the script that submits them.

#include "actionshift/eval/plan_expand.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::eval {

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
