#pragma once
/// \file The append-only result store of one job: `<out>/<id>.jsonl` plus `<out>/<id>.summary.json`.
///
/// Each record is appended as one whole line by a single write(2) and flushed to the kernel at once,
/// so a killed process leaves at most one torn (unterminated: no trailing newline) last line. Opening
/// the store validates every existing line, repairs such a tail by truncation, and refuses (without
/// touching the file) anything else that is wrong, including a complete last line that does not parse. The store also holds an exclusive flock(2) on the
/// JSONL file, so two processes cannot run the same job into the same directory at once.

#include "actionshift/eval/job.hpp"
#include "actionshift/eval/record.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::eval {

/// Version of the job summary (docs/formats.md §3). 2.0 added `records_sha256`; a 1.0 summary is still
/// read (its counts are checked against the records, which it has no hash of).
inline constexpr std::string_view kJobSummarySchemaVersion = "2.0";

/// SHA-256 (64-hex) of the first `n` records of a JSONL results file: of its bytes from the start up to
/// and including the `\n` that ends line `n` (sha256 of no bytes for n = 0). nullopt if `jsonl_bytes`
/// holds fewer than `n` newline-terminated lines.
std::optional<std::string> records_sha256(std::string_view jsonl_bytes, std::int64_t n);

/// A job summary read back and checked on its own (read_job_summary).
struct CheckedSummary {
  std::string path;                           ///< the summary file
  std::string schema_version;                 ///< "2.0", or "1.0" (no records hash)
  JobSpec job;                                ///< its job spec (job_id(job) is the file's id)
  std::int64_t episodes_done{0};              ///< records it covers: the first episodes_done lines of the JSONL file
  std::optional<std::string> records_sha256;  ///< records_sha256 of those lines; none in a 1.0 summary
  std::int64_t successes_once{0};             ///< its success_once count (0 when no episode)
  std::int64_t successes_at_end{0};           ///< its success_at_end count
  std::int64_t episodes_with_safety_flags{0};
};

/// Parse the text of `<id>.summary.json` (read from `path`). Throws actionshift::InputError(path,
/// field, reason) when it is not a summary of job `id`: not JSON (truncated), a missing, mistyped or
/// (schema 2.0) unknown key, an unsupported schema, a job spec of another job, counts that contradict
/// each other.
CheckedSummary parse_job_summary(std::string_view text, const std::string& path, const std::string& id);

/// The records of a JSONL file (`jsonl_bytes`, and `records`, its complete lines parsed) against its
/// summary: the file must hold at least the summary's episodes_done complete lines, their bytes must
/// hash to its records_sha256 (schema 2.0), and its success and safety-flag counts must be those of
/// the records it covers. Records after them (a job running, or killed before writing its summary)
/// are not covered. Throws actionshift::InputError naming `jsonl_path` (records edited or removed)
/// or the summary (counts that are not its records').
void check_records_against_summary(const CheckedSummary& summary, const std::string& jsonl_path, std::string_view jsonl_bytes,
                                   const std::vector<EpisodeRecord>& records);

/// The first part of check_records_against_summary, before the records are parsed: the covered lines
/// exist and hash to the summary's records_sha256 (an edit that breaks a record's JSON is reported as
/// a hash mismatch, not as a parse error).
void check_records_hash(const CheckedSummary& summary, const std::string& jsonl_path, std::string_view jsonl_bytes);

/// Options of ResultStore::open.
struct StoreOptions {
  bool fsync{false};             ///< fsync(2) after every appended line (slower; survives power loss)
  std::ostream* log{nullptr};    ///< where repairs are logged (one line each); nullptr: silent
};

/// An open job result file. Move-only; closes (and unlocks) the file on destruction.
class ResultStore {
 public:
  /// Create `out_dir` if needed, open or create `<out_dir>/<id>.jsonl`, lock it, and scan it.
  /// Lines must be records 0..k−1 of this job in order (job id, task, split, method, seed, backbone
  /// and contract index all match). A torn last line is truncated away and logged.
  /// Throws actionshift::InputError (`<file>:<line>: <field>: <reason>`) on anything else, leaving
  /// the file unmodified, or if another process holds the lock.
  ///
  /// Growing a job: when the file is new (empty) and `out_dir` holds a *sibling* — a job whose spec
  /// differs from this one only in `episodes` (same family_key, read from its `<id>.summary.json`) —
  /// its leading records (episode indices 0..k−1, k ≤ this job's episodes; the sibling with the most)
  /// are copied in with this job's id, so only the missing episodes run. Episodes are a pure function
  /// of (seed, contract index, episode index), so the copies equal what a fresh run would write
  /// (docs/formats.md, "Growing a job").
  static ResultStore open(const std::string& out_dir, const JobSpec& job, const StoreOptions& options = {});

  ResultStore(ResultStore&& other) noexcept;
  ResultStore& operator=(ResultStore&& other) noexcept;
  ResultStore(const ResultStore&) = delete;
  ResultStore& operator=(const ResultStore&) = delete;
  ~ResultStore();

  const JobSpec& job() const noexcept { return job_; }
  const std::string& job_id() const noexcept { return id_; }
  const std::string& jsonl_path() const noexcept { return path_; }          ///< `<out>/<id>.jsonl`
  const std::string& summary_path() const noexcept { return summary_path_; }  ///< `<out>/<id>.summary.json`
  /// Records present: existing ones from the scan, then those appended.
  const std::vector<EpisodeRecord>& records() const noexcept { return records_; }
  std::int64_t episodes_done() const noexcept { return static_cast<std::int64_t>(records_.size()); }
  bool complete() const noexcept { return episodes_done() >= job_.episodes; }
  /// Bytes removed from a torn tail when the store was opened (0: none).
  std::int64_t repaired_bytes() const noexcept { return repaired_bytes_; }
  /// Records copied from a sibling job when the store was opened (0: none), and that job's id.
  std::int64_t adopted() const noexcept { return adopted_; }
  const std::string& adopted_from() const noexcept { return adopted_from_; }
  /// Records the job's existing `<id>.summary.json` vouches for, checked against the file when it was
  /// opened (check_records_against_summary); nullopt without a summary or with a 1.0 summary (no
  /// hash). A summary that does not match its records makes open() throw instead.
  std::optional<std::int64_t> summarized() const noexcept { return summarized_; }
  /// records_sha256 of records(): SHA-256 of the bytes the file holds for them (kept as they are
  /// read and appended, not re-read from disk).
  std::string records_sha256() const;

  /// Append the next record. It must carry this job's id and episode_index == episodes_done().
  /// Throws std::invalid_argument otherwise, and std::runtime_error if the write fails.
  void append(const EpisodeRecord& record);

 private:
  ResultStore() = default;
  void adopt_from_sibling(const std::string& out_dir, const StoreOptions& options);
  JobSpec job_;
  std::string id_, path_, summary_path_;
  std::vector<EpisodeRecord> records_;
  std::int64_t repaired_bytes_{0};
  std::int64_t adopted_{0};
  std::string adopted_from_;
  std::optional<std::int64_t> summarized_;
  struct Digest;                    // running SHA-256 of the records' bytes
  std::unique_ptr<Digest> digest_;
  bool fsync_{false};
  int fd_{-1};
};

/// A job's identity without its episode count: canonical JSON of job_identity_json minus "episodes".
/// Jobs with equal family keys run the same episodes; the one with more episodes extends the other.
std::string family_key(const JobSpec& job);

/// Check that `r` is record `episode_index` of `job` (id `id`): throws actionshift::InputError(source,
/// field, reason) naming the first field that differs.
void check_record_belongs(const EpisodeRecord& r, const JobSpec& job, const std::string& id,
                          std::int64_t episode_index, const std::string& source);

/// The job summary object (docs/formats.md "Job summary"): counts, success rates with Wilson
/// intervals (null when no episode exists), means, safety-flag counts, per-contract rates, the wall
/// time and episodes of this invocation, `message`, and `records_sha256` (the records' bytes in the
/// JSONL file: ResultStore::records_sha256).
nlohmann::json make_job_summary(const JobSpec& job, const std::vector<EpisodeRecord>& records,
                                std::int64_t episodes_run, double wall_time_s, const std::string& message,
                                const std::string& records_sha256);

/// Write a summary atomically (temporary file, fsync, rename) as indented JSON with a final newline.
void write_json_atomic(const std::string& path, const nlohmann::json& value);

}  // namespace actionshift::eval
