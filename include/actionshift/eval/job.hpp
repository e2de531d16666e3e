#pragma once
/// \file Job specifications and their content-hash ids (docs/formats.md "Job spec").
///
/// A job is everything that determines an evaluation's episodes: task, split (name, manifest hash and
/// contract count), method and parameters, backbone and its hash, pool, calibration, rotation mode,
/// seed and episode count. Its id is the SHA-256 of its canonical JSON, and its results live in
/// `<out>/<id>.jsonl` and `<out>/<id>.summary.json`.

#include "actionshift/core/vocabulary.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::eval {

/// Version of the job spec canonical JSON.
/// 3.0: episodes are dealt to contracts by a seeded permutation per block and every contract of a block
/// starts from the same initial state (episode_slot, episode_seed); 2.0 ids named round-robin dealing
/// with per-contract initial states, which let a first observation identify the hidden contract.
inline constexpr std::string_view kJobSchemaVersion = "3.0";

/// A split manifest by content hash, with the number of evaluation contracts it holds. Its identity is
/// the hash; the name is a label (records and summary cells carry it). A split given as a file has its
/// path recorded, not hashed (like RobotRef::urdf): the job is resolved from that file, not by name.
struct SplitRef {
  std::string name;             ///< e.g. "seen" (the manifest's own name)
  std::string sha256;           ///< 64-hex manifest hash (`manifest_sha256`)
  std::int64_t contracts{0};    ///< number of evaluation contracts (> 0)
  std::string path{};           ///< absolute manifest file the job was made from; empty: the built-in `name`
  bool operator==(const SplitRef&) const = default;
};

/// A backbone (frozen policy) by name and content hash.
struct BackboneRef {
  std::string name;             ///< e.g. "expert", "mlp", "external:<command>"
  std::string sha256;           ///< 64-hex hash of its weights or description
  bool operator==(const BackboneRef&) const = default;
};

/// A declared contract pool by content hash (pool-privileged methods only); the name is a label and a
/// pool given as a file has its path recorded, not hashed (as SplitRef).
struct PoolRef {
  std::string name;             ///< e.g. "reference9"
  std::string sha256;           ///< 64-hex `pool_sha256`
  std::string path{};           ///< absolute manifest file the job was made from; empty: the built-in `name`
  bool operator==(const PoolRef&) const = default;
};

/// A robot description other than the embedded Panda (`--robot URDF --package NAME=DIR`). Only its
/// content hash enters the job id; the paths say where to load it from (they are recorded, not hashed,
/// so moving the files does not change the job).
struct RobotRef {
  std::string sha256;                            ///< 64-hex content hash (URDF + collision meshes)
  std::string urdf;                              ///< absolute URDF path
  std::map<std::string, std::string> packages;   ///< package name -> absolute directory
  bool operator==(const RobotRef&) const = default;
};

/// The files an external policy reads (`--policy-files FILE...`: its script, weights, configuration).
/// Only their content hash enters the job id, so editing the policy's script makes a new job.
struct PolicyFilesRef {
  std::string sha256;                ///< files_content_sha256(paths)
  std::vector<std::string> paths;    ///< absolute paths, as given (recorded, not hashed)
  bool operator==(const PolicyFilesRef&) const = default;
};

/// A user method's identity (adapt::register_method; docs/methods.md): what it is, not only what it is
/// called. Its kind, declared version, rung and content hash enter the job id; the paths of its files
/// are recorded, not hashed.
struct MethodPluginRef {
  std::string kind;                  ///< "cpp", "python" or "external"
  std::string version;               ///< declared version
  std::string rung;                  ///< "pool", "grammar" or "none"
  std::string sha256;                ///< adapt::PluginIdentity::sha256
  std::vector<std::string> files;    ///< absolute paths of its files (recorded, not hashed)
  bool operator==(const MethodPluginRef&) const = default;
};

/// sha256_hex(canonical_json([sha256_hex(bytes of each file)] sorted)): the content of a set of files,
/// independent of their names, locations and order. Throws actionshift::InputError(path, field,
/// "cannot read file") for an unreadable one and for an empty list.
std::string files_content_sha256(const std::vector<std::string>& paths, const std::string& field = "--policy-files");


/// Everything that determines a job's episodes. Equality of ids (not of structs) is identity:
/// `method_params` is compared as text here but hashed in canonical form.
struct JobSpec {
  std::string task;                          ///< task name, e.g. "pick_cube"
  SplitRef split;                            ///< evaluation split
  std::string method;                        ///< method name, e.g. "oracle", "no_adapt"
  std::string method_params{"{}"};           ///< JSON object text of the method's parameters
  std::optional<MethodPluginRef> method_plugin;  ///< a registered user method's identity, or none (a built-in)
  BackboneRef backbone;                      ///< frozen policy
  std::optional<PoolRef> pool;               ///< declared pool, or none
  std::optional<std::string> calibration_sha256;  ///< 64-hex calibration hash, or none
  std::string rotation_mode{"live"};         ///< a name of actionshift::kRotationModes (core/vocabulary.hpp)
  std::string profile{"maniskill"};          ///< a name of actionshift::kProfiles: the simulator fidelity profile
  std::uint64_t seed{0};                     ///< experimental seed
  std::int64_t episodes{0};                  ///< number of episodes (> 0)
  std::optional<RobotRef> robot;             ///< robot description; none = the embedded Panda
  std::optional<PolicyFilesRef> policy_files;  ///< files of an external policy, or none
  /// Observation (sensor) noise sigma of the environment (sim::EnvConfig::obs_noise, docs/sim.md §6.1):
  /// 0 (default, off) or in (0, 0.1]. Hashed and recorded only when non-zero, so ids of jobs without noise are unchanged.
  double obs_noise{0.0};
  /// Control steps per episode (sim::EnvConfig::horizon): 0 (default) is the task's (50; peg_insertion_side
  /// 100), else 1..sim::kMaxHorizon (the reference evaluates its Diffusion Policy at 100). Hashed and recorded
  /// only when non-zero, so ids of jobs at the task's horizon are unchanged.
  int horizon{0};
  bool operator==(const JobSpec&) const = default;
};

/// Largest episode count a job may have.
inline constexpr std::int64_t kMaxJobEpisodes = 1'000'000'000;

/// Throws actionshift::InputError(source, field, reason) if a field is invalid.
void validate_job(const JobSpec& job, const std::string& source = "job");

/// The hashed object: {"backbone":{"name","sha256"},"calibration_sha256","episodes",
/// "method":{"name","params"} (plus "plugin":{"files","kind","rung","sha256","version"} for a user method),"pool":{"name","sha256"}|null,"profile","rotation_mode","schema_version",
/// "seed","split":{"contracts","name","sha256"},"task"}, plus "robot":{"packages","sha256","urdf"}
/// only when the job names a robot, "policy_files":{"paths","sha256"} only when it names policy
/// files, "obs_noise" (a float) and "horizon" (an integer) only when non-zero, and "path" in "split" / "pool" only when the
/// manifest was given as a file. Validates first.
nlohmann::json job_to_json(const JobSpec& job);

/// The identity object: job_to_json with "robot" and "policy_files" reduced to {"sha256"}, without
/// "split.path" / "pool.path" (a split's identity is its manifest_sha256) and without the method plug-in's
/// "files" (paths are not identity).
nlohmann::json job_identity_json(const JobSpec& job);

/// Canonical JSON text of job_identity_json (sorted keys, no whitespace, Python-repr floats).
std::string job_canonical_json(const JobSpec& job);

/// The job id: lowercase 64-hex SHA-256 of job_canonical_json.
std::string job_id(const JobSpec& job);

/// Inverse of job_to_json; `source` names the document in errors. Unknown keys are rejected.
JobSpec job_from_json(const nlohmann::json& j, const std::string& source);

/// `<id>.jsonl`
std::string jsonl_file_name(std::string_view id);
/// `<id>.summary.json`
std::string summary_file_name(std::string_view id);

/// Where episode `episode_index` of a job runs.
struct EpisodeSlot {
  std::int64_t contract_index{0};     ///< the contract it runs (see episode_slot)
  std::int64_t contract_episode{0};   ///< episode_index div contracts: its block, and its index within the contract
};

/// Episodes are dealt in blocks of n = `contracts`: episode i belongs to block b = i div n and runs
/// contract π_b(i mod n), where π_b is a permutation of 0..n−1 drawn from (seed, b) (deal_permutation).
/// Every contract runs once per full block, so a job of N episodes gives each contract ⌊N/n⌋ or ⌈N/n⌉;
/// which contract runs at which position is not public without the seed, so a process that counts its
/// resets does not learn the contract. Throws std::invalid_argument if contracts ≤ 0 or episode_index < 0.
EpisodeSlot episode_slot(std::uint64_t seed, std::int64_t contracts, std::int64_t episode_index);

/// π_b: a Fisher–Yates shuffle of 0..n−1 (for j = n−1 … 1 swap positions j and x_j mod (j+1)), where
/// x_{n−1} = splitmix64(s), x_{j−1} = splitmix64(x_j) and s = splitmix64(splitmix64(seed ^ D) ^ block)
/// for a fixed domain constant D.
std::vector<std::int64_t> deal_permutation(std::uint64_t seed, std::int64_t contracts, std::int64_t block);

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): x + 0x9E3779B97F4A7C15, then
/// xor-shift-multiply by 0xBF58476D1CE4E5B9 (>>30) and 0x94D049BB133111EB (>>27), then ^ (>>31).
std::uint64_t splitmix64(std::uint64_t x) noexcept;

/// An episode's environment seed, the only source of its randomness (initial state, observation noise):
/// splitmix64(splitmix64(splitmix64(seed) ^ D) ^ contract_episode) for a fixed domain constant D.
/// It depends on the job's seed and the episode's block only, so **every contract of the split sees the
/// same initial states** (a paired design): neither the first observation nor the initial tool rotation
/// carries information about which contract is hidden, and methods and contracts pair episode by episode.
std::uint64_t episode_seed(std::uint64_t seed, std::int64_t contract_episode) noexcept;

/// The seed handed to the adapter (Adapter::begin_episode): splitmix64(splitmix64(seed ^ D) ^
/// contract_episode) with a fixed domain constant D. Like episode_seed it depends only on the job's seed
/// and the episode's block, so it is the same for every contract of the split: an adapter cannot invert
/// it to the contract index. (episode_seed, which fixes the initial state, stays with the environment.)
std::uint64_t adapter_episode_seed(std::uint64_t seed, std::int64_t contract_episode) noexcept;

}  // namespace actionshift::eval
