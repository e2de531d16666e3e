#pragma once
/// \file The episode runner: runs a job's missing episodes on worker threads and appends their
/// records in episode order, so the JSONL file is byte-identical for any thread count and after any
/// number of kills and resumes.

#include "actionshift/core/vocabulary.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/record.hpp"

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>

namespace actionshift::eval {

/// What an episode function is asked to run.
struct EpisodeTask {
  const JobSpec* job{nullptr};        ///< the job (never null inside run_job)
  std::uint64_t seed{0};              ///< the job's experimental seed
  std::int64_t contract_index{0};     ///< contract of the split (episode_slot: a seeded deal per block)
  std::int64_t contract_episode{0};   ///< the episode's block: its index within its contract
  std::int64_t episode_index{0};      ///< index of the episode within the job
  std::uint64_t episode_seed{0};      ///< episode_seed(seed, contract_episode): the environment's, the same for every contract
  std::uint64_t adapter_seed{0};      ///< adapter_episode_seed(seed, contract_episode): the only seed an adapter gets
  unsigned worker{0};                 ///< worker thread index in [0, threads): key per-worker state on it
};

/// The task of episode `episode_index` of `job` exactly as run_job hands it to a worker: its
/// contract slot (episode_slot) and seed (episode_seed). Throws std::invalid_argument for an index
/// outside [0, job.episodes).
EpisodeTask episode_task(const JobSpec& job, std::int64_t episode_index, unsigned worker = 0);

/// Stamp the job fields of an episode function's record exactly as run_job does before writing it:
/// schema_version, job_id, task, split, method, seed, contract_index, episode_index, backbone,
/// backbone_sha256.
void stamp_record(EpisodeRecord& r, const JobSpec& job, const std::string& job_id, const EpisodeTask& task);

/// Runs one episode. Called concurrently from several threads (each worker index from one thread at
/// a time). It must be deterministic in the task, fill `contract_sha256` and the outcome fields
/// (success_once, success_at_end, task_return, steps, probe_steps, probe_displacement,
/// safety_flags), and may leave the job fields empty: the runner stamps schema_version, job_id,
/// task, split, method, seed, contract_index, episode_index, backbone and backbone_sha256.
using EpisodeFn = std::function<EpisodeRecord(const EpisodeTask&)>;

/// How progress is shown.
enum class ProgressMode {
  automatic,  ///< `bar` when stderr is a terminal, `lines` otherwise
  bar,        ///< one self-overwriting line: bar, episodes, episodes/s, ETA
  lines,      ///< a plain log line about every 5 s, and one at the end
  off,        ///< nothing
};
/// The names of the progress modes (CLI `--progress`, Python `evaluate(progress=...)`).
inline constexpr auto kProgressModes = make_vocabulary<ProgressMode>(
    "progress mode", Vocabulary<ProgressMode, 4>::Entry{ProgressMode::automatic, "auto"},
    Vocabulary<ProgressMode, 4>::Entry{ProgressMode::bar, "bar"}, Vocabulary<ProgressMode, 4>::Entry{ProgressMode::lines, "lines"},
    Vocabulary<ProgressMode, 4>::Entry{ProgressMode::off, "off"});
inline std::string_view progress_mode_name(ProgressMode m) { return kProgressModes.name(m); }
inline ProgressMode parse_progress_mode(std::string_view text, const std::string& source = "",
                                        const std::string& field = "--progress") {
  return kProgressModes.parse(text, source, field);
}

/// Options of run_job.
struct RunOptions {
  unsigned threads{0};                 ///< worker threads; 0: std::thread::hardware_concurrency()
  std::string out_dir{"results"};      ///< results directory
  ProgressMode progress{ProgressMode::automatic};  ///< progress display
  bool fsync{false};                   ///< fsync after every line
  std::ostream* log{nullptr};          ///< progress and repair messages; nullptr: std::cerr
  /// Polled by the calling thread about every 100 ms while it waits for episodes (not by the
  /// workers). Returning true stops the job as a failing episode would: no new episode starts, the
  /// finished ones are written in order, the summary says where it stopped, and run_job throws
  /// Interrupted. Python's evaluate() checks for Ctrl-C here.
  std::function<bool()> interrupted;
};

/// Thrown by run_job when RunOptions::interrupted returned true.
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What run_job did.
struct RunResult {
  std::string job_id;                  ///< 64-hex id
  std::string jsonl_path;              ///< `<out>/<id>.jsonl`
  std::string summary_path;            ///< `<out>/<id>.summary.json`
  std::int64_t episodes_total{0};      ///< the job's episode count
  std::int64_t episodes_before{0};     ///< records present before this call
  std::int64_t episodes_run{0};        ///< records appended by this call
  bool already_complete{false};        ///< nothing was left to run (the call was a no-op)
  double wall_time_s{0.0};             ///< [s] wall time of this call
};

/// Run the missing episodes of `job` into `options.out_dir` and write its summary.
/// A complete job is a no-op (its summary is only written if missing). If `fn` throws or returns an
/// invalid record, the records before the failing episode are still written in order, the summary
/// says where it stopped, and the exception is rethrown; re-running resumes from there.
/// Throws actionshift::InputError for an invalid job or a results file that is not this job's.
RunResult run_job(const JobSpec& job, const EpisodeFn& fn, const RunOptions& options = {});

}  // namespace actionshift::eval
