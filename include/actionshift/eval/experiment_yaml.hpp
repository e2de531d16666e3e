#pragma once
/// \file Experiment files: an experiment YAML (`configs/experiments/<name>.yaml`, docs/formats.md
/// "Experiment") parsed into an Experiment, the grid of jobs it names before any name is resolved.
/// plan_expand.hpp turns it into a Plan.

#include <cstdint>
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
/// default "maniskill"), horizon (control steps per episode, default the task's), description (free text).
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
  int horizon{0};                     ///< control steps per episode; 0 (default): the task's
};

/// Parse experiment YAML text. `source` names it in errors.
/// Throws actionshift::InputError(source, field, reason) for malformed YAML (source gets `:line`),
/// an unknown or missing key, a wrong type, an empty or duplicated list entry.
Experiment parse_experiment(std::string_view yaml_text, const std::string& source);

/// Read and parse an experiment file (as parse_experiment; a missing file is an InputError).
Experiment load_experiment(const std::string& path);

/// Most jobs one plan may hold. The largest committed experiment (tournament.yaml) has 936; a plan
/// file costs about 1.2 KB per job, so 100,000 jobs are a 120 MB plan (an 80 KB experiment used to
/// expand to 180,000 jobs and a 220 MB plan). parse_experiment, make_plan and plan_from_json check it
/// from the list sizes, before any job is expanded or read.
inline constexpr std::uint64_t kMaxPlanJobs = 100000;

/// tasks × splits × methods × seeds of `ex`, saturating at UINT64_MAX.
std::uint64_t experiment_job_count(const Experiment& ex);

}  // namespace actionshift::eval
