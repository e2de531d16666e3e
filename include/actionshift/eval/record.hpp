#pragma once
/// \file The per-episode result record: one canonical JSON line per episode in `<job id>.jsonl`
/// (schema in docs/formats.md).

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::eval {

/// Version of the episode record schema written by this library.
inline constexpr std::string_view kRecordSchemaVersion = "2.0";

/// One evaluated episode. A value type: the runner stamps the job fields, the episode function fills
/// the outcome fields.
struct EpisodeRecord {
  /// "2.0": 2.0 added `method_variant` and paired initial states (eval/job.hpp episode_seed); 1.1 added
  /// `profile`. Records of 1.x are refused: their episodes were dealt and seeded differently.
  std::string schema_version{kRecordSchemaVersion};
  std::string job_id;           ///< 64-hex job id (eval/job.hpp)
  std::string task;             ///< task name, e.g. "pick_cube"
  std::string split;            ///< split name, e.g. "seen"
  std::string method;           ///< method name, e.g. "oracle"
  /// The method variant's label (eval::method_variant): the bare name for the paper's method, e.g.
  /// "entropy_probes", or "entropy_probes{calibrated}", "dualabi{tau=0.5}". Summary cells key on it.
  std::string method_variant;
  std::uint64_t seed{0};        ///< experimental seed of the job
  std::int64_t contract_index{0};   ///< index of the contract in the split's evaluation list
  std::string contract_sha256;  ///< 64-hex hash of that contract's canonical JSON
  std::int64_t episode_index{0};    ///< 0-based index of the episode within the job
  bool success_once{false};     ///< task success reached at any step
  bool success_at_end{false};   ///< task success at the last step
  double task_return{0.0};      ///< sum of rewards (JSON key `return`)
  std::int64_t steps{0};        ///< control steps taken (≥ 0)
  std::int64_t probe_steps{0};  ///< steps on which the adapter probed (≥ 0)
  double probe_displacement{0.0};   ///< [m] TCP translation during probe steps (≥ 0)
  std::vector<std::string> safety_flags;  ///< names of the safety checks that fired (unique)
  std::string backbone;         ///< backbone (frozen policy) name
  std::string backbone_sha256;  ///< 64-hex hash of the backbone's weights or description
  std::string profile{"maniskill"};  ///< simulator fidelity profile of the job ("maniskill", "ideal")
  double obs_noise{0.0};            ///< the job's observation-noise sigma (key `obs_noise` written only when non-zero)
  std::string actionshift_version;  ///< provenance: version of the build that wrote the record ("" → no `provenance` key)
  std::string git_commit;           ///< provenance: its configure-time git commit ("" → null)

  bool operator==(const EpisodeRecord&) const = default;
};

/// The record as a JSON object (keys as in docs/formats.md).
nlohmann::json to_json(const EpisodeRecord& r);

/// The record as one canonical JSON line (sorted keys, no whitespace, Python-repr floats), without
/// the trailing newline. Validates first: throws std::invalid_argument naming the field if the record
/// is invalid (see validate_record).
std::string to_jsonl_line(const EpisodeRecord& r);

/// Throws actionshift::InputError(source, field, reason) if a field is out of its domain: empty
/// names, malformed hashes, negative counts, non-finite numbers, empty or duplicate safety flags.
void validate_record(const EpisodeRecord& r, const std::string& source = "episode record");

/// Parse one JSONL line. `source` names the line in errors, e.g. "results/ab12.jsonl:7".
/// Throws actionshift::InputError(source, field, reason) for malformed JSON, a missing or unknown key,
/// a wrong type or an invalid value.
EpisodeRecord parse_record_line(std::string_view line, const std::string& source);

/// Parse a record from a JSON object (as parse_record_line).
EpisodeRecord record_from_json(const nlohmann::json& j, const std::string& source);

/// Result of reading a whole JSONL file.
struct RecordFile {
  std::vector<EpisodeRecord> records;  ///< complete, valid lines in file order
  bool torn_tail{false};               ///< the file ended in an unterminated line that was ignored
};

/// Read every line of a JSONL results file. Every newline-terminated line must be a valid record
/// (errors name `<path>:<line>`). An unterminated last line is an error unless `allow_torn_tail`, in
/// which case it is ignored and reported in `torn_tail` (a job may still be writing).
/// Throws actionshift::InputError if the file cannot be read.
RecordFile read_record_file(const std::string& path, bool allow_torn_tail = false);

}  // namespace actionshift::eval
