#include "actionshift/core/input_file.hpp"
#include "actionshift/eval/job.hpp"

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/sim/env.hpp"
#include "io.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <optional>
#include <set>

namespace actionshift::eval {

namespace {

using nlohmann::json;

void check_hash(const std::string& v, const std::string& src, const std::string& field) {
  if (!is_sha256_hex(v)) throw InputError(src, field, "expected 64 lowercase hex digits (got " + quote_input(v, '"') + ")");
}

void check_token(const std::string& v, const std::string& src, const std::string& field) {
  if (!detail::is_token(v)) throw InputError(src, field, "expected a name of [a-z0-9_.-] (got " + quote_input(v, '"') + ")");
}

void check_keys(const json& j, const std::set<std::string>& allowed, const std::string& src, const std::string& prefix) {
  if (!j.is_object()) throw InputError(src, prefix.empty() ? "" : prefix, "expected an object (got " + json_for_message(j) + ")");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!allowed.count(it.key())) throw InputError(src, prefix.empty() ? it.key() : prefix + "." + it.key(), "unknown field");
  for (const auto& k : allowed)
    if (!j.contains(k)) throw InputError(src, prefix.empty() ? k : prefix + "." + k, "missing field");
}

// a JSON integer ≥ 0, signed or unsigned (values built in memory are signed, parsed ones unsigned)
std::optional<std::uint64_t> nonneg_int(const json& v) {
  if (v.is_number_unsigned()) return v.get<std::uint64_t>();
  if (v.is_number_integer() && v.get<std::int64_t>() >= 0) return static_cast<std::uint64_t>(v.get<std::int64_t>());
  return std::nullopt;
}

std::string str_at(const json& j, const char* key, const std::string& src, const std::string& field) {
  const json& v = j.at(key);
  if (!v.is_string()) throw InputError(src, field, "expected a string (got " + json_for_message(v) + ")");
  return v.get<std::string>();
}

// a recorded manifest path: empty (a built-in manifest by name) or an absolute path
void check_manifest_path(const std::string& path, const std::string& src, const std::string& field) {
  if (!path.empty() && path.front() != '/')
    throw InputError(src, field, "must be an absolute path (got " + quote_input(path, '"') + ")");
}

json parse_params(const std::string& text, const std::string& src) {
  const json p = parse_json_input(text, src, "method.params");
  if (!p.is_object()) throw InputError(src, "method.params", "expected a JSON object (got " + json_for_message(p) + ")");
  return p;
}

}  // namespace

void validate_job(const JobSpec& job, const std::string& src) {
  check_token(job.task, src, "task");
  check_token(job.split.name, src, "split.name");
  check_hash(job.split.sha256, src, "split.sha256");
  if (job.split.contracts <= 0) throw InputError(src, "split.contracts", "must be > 0 (got " + std::to_string(job.split.contracts) + ")");
  // an external method is named by its command (`external:<command>`), like an external backbone
  if (!(job.method_plugin && job.method_plugin->kind == "external" && job.method.starts_with("external:")))
    check_token(job.method, src, "method.name");
  if (job.method_plugin) {
    const auto& m = *job.method_plugin;
    if (m.kind != "cpp" && m.kind != "python" && m.kind != "external")
      throw InputError(src, "method.plugin.kind", "expected cpp, python or external (got " + quote_input(m.kind, '"') + ")");
    if (m.rung != "pool" && m.rung != "grammar" && m.rung != "none")
      throw InputError(src, "method.plugin.rung", "expected pool, grammar or none (got " + quote_input(m.rung, '"') + ")");
    if (m.version.empty()) throw InputError(src, "method.plugin.version", "must not be empty");
    check_hash(m.sha256, src, "method.plugin.sha256");
  }
  const json params = parse_params(job.method_params, src);
  try {
    (void)canonical_dump(params);  // rejects non-finite floats
  } catch (const std::invalid_argument& e) {
    throw InputError(src, "method.params", e.what());
  }
  if (job.backbone.name.empty()) throw InputError(src, "backbone.name", "must not be empty");
  check_hash(job.backbone.sha256, src, "backbone.sha256");
  if (job.pool) {
    check_token(job.pool->name, src, "pool.name");
    check_hash(job.pool->sha256, src, "pool.sha256");
  }
  check_manifest_path(job.split.path, src, "split.path");
  if (job.pool) check_manifest_path(job.pool->path, src, "pool.path");
  if (job.calibration_sha256) check_hash(*job.calibration_sha256, src, "calibration_sha256");
  (void)parse_rotation_mode(job.rotation_mode, src, "rotation_mode");
  (void)parse_profile(job.profile, src, "profile");
  if (job.episodes <= 0) throw InputError(src, "episodes", "must be > 0 (got " + std::to_string(job.episodes) + ")");
  // a billion episodes is days of a cluster; a larger count is a typo (or a saturated parse of one)
  if (job.episodes > kMaxJobEpisodes)
    throw InputError(src, "episodes", "must be at most " + std::to_string(kMaxJobEpisodes) + " (got " + std::to_string(job.episodes) + ")");
  if (!(job.obs_noise >= 0.0 && job.obs_noise <= sim::kMaxObsNoise)) {  // also rejects NaN
    std::ostringstream got;
    got << job.obs_noise;
    throw InputError(src, "obs_noise", "must be a finite sigma in [0, 0.1] (metres / radians; got " + got.str() + ")");
  }
  sim::check_horizon(job.horizon, src);
  if (job.policy_files) {
    check_hash(job.policy_files->sha256, src, "policy_files.sha256");
    if (job.policy_files->paths.empty()) throw InputError(src, "policy_files.paths", "must name at least one file");
  }
  if (job.robot) {
    check_hash(job.robot->sha256, src, "robot.sha256");
    if (job.robot->urdf.empty()) throw InputError(src, "robot.urdf", "must not be empty");
    for (const auto& [name, dir] : job.robot->packages)
      if (name.empty() || dir.empty()) throw InputError(src, "robot.packages", "names and directories must not be empty");
  }
}

nlohmann::json job_to_json(const JobSpec& job) {
  validate_job(job);
  json j = json::object();
  j["schema_version"] = std::string(kJobSchemaVersion);
  j["task"] = job.task;
  j["split"] = {{"name", job.split.name}, {"sha256", job.split.sha256}, {"contracts", job.split.contracts}};
  if (!job.split.path.empty()) j["split"]["path"] = job.split.path;
  j["method"] = {{"name", job.method}, {"params", parse_params(job.method_params, "job")}};
  if (job.method_plugin)
    j["method"]["plugin"] = {{"kind", job.method_plugin->kind},     {"version", job.method_plugin->version},
                             {"rung", job.method_plugin->rung},     {"sha256", job.method_plugin->sha256},
                             {"files", job.method_plugin->files}};
  j["backbone"] = {{"name", job.backbone.name}, {"sha256", job.backbone.sha256}};
  j["pool"] = job.pool ? json{{"name", job.pool->name}, {"sha256", job.pool->sha256}} : json(nullptr);
  if (job.pool && !job.pool->path.empty()) j["pool"]["path"] = job.pool->path;
  j["calibration_sha256"] = job.calibration_sha256 ? json(*job.calibration_sha256) : json(nullptr);
  j["rotation_mode"] = job.rotation_mode;
  j["profile"] = job.profile;
  j["seed"] = job.seed;
  j["episodes"] = job.episodes;
  if (job.robot) {
    json packages = json::object();
    for (const auto& [name, dir] : job.robot->packages) packages[name] = dir;
    j["robot"] = {{"sha256", job.robot->sha256}, {"urdf", job.robot->urdf}, {"packages", packages}};
  }
  if (job.policy_files) j["policy_files"] = {{"sha256", job.policy_files->sha256}, {"paths", job.policy_files->paths}};
  if (job.obs_noise != 0.0) j["obs_noise"] = job.obs_noise;
  if (job.horizon != 0) j["horizon"] = job.horizon;
  return j;
}

nlohmann::json job_identity_json(const JobSpec& job) {
  json j = job_to_json(job);
  if (job.robot) j["robot"] = {{"sha256", job.robot->sha256}};
  if (job.policy_files) j["policy_files"] = {{"sha256", job.policy_files->sha256}};
  if (job.method_plugin) j["method"]["plugin"].erase("files");
  // a manifest's identity is its content hash: where the file lives is recorded, not hashed
  j["split"].erase("path");
  if (job.pool) j["pool"].erase("path");
  return j;
}

std::string job_canonical_json(const JobSpec& job) { return canonical_dump(job_identity_json(job)); }

std::string job_id(const JobSpec& job) { return sha256_hex(job_canonical_json(job)); }

JobSpec job_from_json(const nlohmann::json& j, const std::string& src) {
  if (j.is_object() && j.contains("horizon")) {  // optional: present only for a horizon other than the task's
    json rest = j;
    rest.erase("horizon");
    JobSpec job = job_from_json(rest, src);
    const json& v = j.at("horizon");
    if (!v.is_number_integer()) throw InputError(src, "horizon", "expected an integer number of control steps");
    const auto h = v.get<std::int64_t>();
    sim::check_horizon(h, src);
    job.horizon = static_cast<int>(h);
    validate_job(job, src);
    return job;
  }
  if (j.is_object() && j.contains("obs_noise")) {  // optional: present only for a noisy environment
    json rest = j;
    rest.erase("obs_noise");
    JobSpec job = job_from_json(rest, src);
    const json& v = j.at("obs_noise");
    if (!v.is_number()) throw InputError(src, "obs_noise", "expected a number");
    job.obs_noise = v.get<double>();
    validate_job(job, src);
    return job;
  }
  if (j.is_object() && j.contains("policy_files")) {  // optional: present only for named policy files
    json rest = j;
    rest.erase("policy_files");
    JobSpec job = job_from_json(rest, src);
    const json& p = j.at("policy_files");
    check_keys(p, {"paths", "sha256"}, src, "policy_files");
    PolicyFilesRef ref;
    ref.sha256 = str_at(p, "sha256", src, "policy_files.sha256");
    if (!p.at("paths").is_array()) throw InputError(src, "policy_files.paths", "expected a list of paths");
    for (const auto& v : p.at("paths")) {
      if (!v.is_string()) throw InputError(src, "policy_files.paths", "expected a list of paths");
      ref.paths.push_back(v.get<std::string>());
    }
    job.policy_files = std::move(ref);
    validate_job(job, src);
    return job;
  }
  if (j.is_object() && j.contains("robot")) {  // optional: present only for a user-supplied robot
    json rest = j;
    rest.erase("robot");
    JobSpec job = job_from_json(rest, src);
    const json& r = j.at("robot");
    check_keys(r, {"packages", "sha256", "urdf"}, src, "robot");
    RobotRef ref;
    ref.sha256 = str_at(r, "sha256", src, "robot.sha256");
    ref.urdf = str_at(r, "urdf", src, "robot.urdf");
    if (!r.at("packages").is_object()) throw InputError(src, "robot.packages", "expected an object");
    for (auto it = r.at("packages").begin(); it != r.at("packages").end(); ++it) {
      if (!it.value().is_string()) throw InputError(src, "robot.packages." + it.key(), "expected a string");
      ref.packages[it.key()] = it.value().get<std::string>();
    }
    job.robot = std::move(ref);
    validate_job(job, src);
    return job;
  }
  check_keys(j, {"backbone", "calibration_sha256", "episodes", "method", "pool", "profile", "rotation_mode", "schema_version",
                 "seed", "split", "task"},
             src, "");
  if (j.at("schema_version") != std::string(kJobSchemaVersion))
    throw InputError(src, "schema_version", "unsupported job schema version (got " + json_for_message(j.at("schema_version")) + ")");
  JobSpec job;
  job.task = str_at(j, "task", src, "task");
  // "path" is optional in "split" and "pool": present only for a manifest given as a file
  const auto without_path = [&](const json& m, const char* field, std::string& path) {
    if (!m.is_object() || !m.contains("path")) return m;
    path = str_at(m, "path", src, std::string(field) + ".path");
    if (path.empty()) throw InputError(src, std::string(field) + ".path", "must not be empty (omit it for a built-in manifest)");
    json rest = m;
    rest.erase("path");
    return rest;
  };
  const json split = without_path(j.at("split"), "split", job.split.path);
  check_keys(split, {"contracts", "name", "sha256"}, src, "split");
  job.split.name = str_at(split, "name", src, "split.name");
  job.split.sha256 = str_at(split, "sha256", src, "split.sha256");
  const auto contracts = nonneg_int(split.at("contracts"));
  if (!contracts || *contracts > static_cast<std::uint64_t>(INT64_MAX))
    throw InputError(src, "split.contracts", "expected a positive integer");
  job.split.contracts = static_cast<std::int64_t>(*contracts);
  const json& method = j.at("method");
  if (method.is_object() && method.contains("plugin")) {
    const json& p = method.at("plugin");
    check_keys(p, {"files", "kind", "rung", "sha256", "version"}, src, "method.plugin");
    MethodPluginRef ref;
    ref.kind = str_at(p, "kind", src, "method.plugin.kind");
    ref.version = str_at(p, "version", src, "method.plugin.version");
    ref.rung = str_at(p, "rung", src, "method.plugin.rung");
    ref.sha256 = str_at(p, "sha256", src, "method.plugin.sha256");
    if (!p.at("files").is_array()) throw InputError(src, "method.plugin.files", "expected a list of paths");
    for (const auto& v : p.at("files")) {
      if (!v.is_string()) throw InputError(src, "method.plugin.files", "expected a list of paths");
      ref.files.push_back(v.get<std::string>());
    }
    job.method_plugin = std::move(ref);
    json rest = method;
    rest.erase("plugin");
    check_keys(rest, {"name", "params"}, src, "method");
  } else {
    check_keys(method, {"name", "params"}, src, "method");
  }
  job.method = str_at(method, "name", src, "method.name");
  if (!method.at("params").is_object()) throw InputError(src, "method.params", "expected an object");
  job.method_params = canonical_dump(method.at("params"));
  const json& backbone = j.at("backbone");
  check_keys(backbone, {"name", "sha256"}, src, "backbone");
  job.backbone.name = str_at(backbone, "name", src, "backbone.name");
  job.backbone.sha256 = str_at(backbone, "sha256", src, "backbone.sha256");
  if (!j.at("pool").is_null()) {
    std::string pool_path;
    const json pool = without_path(j.at("pool"), "pool", pool_path);
    check_keys(pool, {"name", "sha256"}, src, "pool");
    job.pool = PoolRef{str_at(pool, "name", src, "pool.name"), str_at(pool, "sha256", src, "pool.sha256"), pool_path};
  }
  const json& cal = j.at("calibration_sha256");
  if (!cal.is_null()) job.calibration_sha256 = str_at(j, "calibration_sha256", src, "calibration_sha256");
  job.rotation_mode = str_at(j, "rotation_mode", src, "rotation_mode");
  job.profile = str_at(j, "profile", src, "profile");
  const auto seed = nonneg_int(j.at("seed"));
  if (!seed) throw InputError(src, "seed", "expected a non-negative integer");
  job.seed = *seed;
  const auto episodes = nonneg_int(j.at("episodes"));
  if (!episodes || *episodes > static_cast<std::uint64_t>(INT64_MAX))
    throw InputError(src, "episodes", "expected a positive integer");
  job.episodes = static_cast<std::int64_t>(*episodes);
  validate_job(job, src);
  return job;
}

std::string files_content_sha256(const std::vector<std::string>& paths, const std::string& field) {
  if (paths.empty()) throw InputError("", field, "name at least one file");
  std::vector<std::string> hashes;
  for (const auto& p : paths) {
    // the whole file or an error: a short or failed read must never be hashed as if it were the file
    std::string bytes;
    try {
      bytes = read_input_file(p, "a policy file", kMaxInputFileBytes);
    } catch (const InputError& e) {
      throw InputError(e.source(), field, e.reason());
    }
    hashes.push_back(sha256_hex(bytes));
  }
  std::sort(hashes.begin(), hashes.end());
  return sha256_hex(canonical_dump(json(hashes)));
}

std::string jsonl_file_name(std::string_view id) { return std::string(id) + ".jsonl"; }
std::string summary_file_name(std::string_view id) { return std::string(id) + ".summary.json"; }

std::uint64_t splitmix64(std::uint64_t x) noexcept {
  std::uint64_t z = x + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::vector<std::int64_t> deal_permutation(std::uint64_t seed, std::int64_t contracts, std::int64_t block) {
  if (contracts <= 0) throw std::invalid_argument("deal_permutation: contracts must be > 0");
  if (block < 0) throw std::invalid_argument("deal_permutation: block must be >= 0");
  constexpr std::uint64_t kDealDomain = 0x6465616c696e67ull;  // "dealing"
  std::uint64_t state = splitmix64(splitmix64(seed ^ kDealDomain) ^ static_cast<std::uint64_t>(block));
  std::vector<std::int64_t> perm(static_cast<std::size_t>(contracts));
  for (std::int64_t k = 0; k < contracts; ++k) perm[static_cast<std::size_t>(k)] = k;
  for (std::int64_t j = contracts - 1; j > 0; --j) {
    state = splitmix64(state);
    const auto k = static_cast<std::int64_t>(state % static_cast<std::uint64_t>(j + 1));
    std::swap(perm[static_cast<std::size_t>(j)], perm[static_cast<std::size_t>(k)]);
  }
  return perm;
}

EpisodeSlot episode_slot(std::uint64_t seed, std::int64_t contracts, std::int64_t episode_index) {
  if (contracts <= 0) throw std::invalid_argument("episode_slot: contracts must be > 0");
  if (episode_index < 0) throw std::invalid_argument("episode_slot: episode_index must be >= 0");
  const std::int64_t block = episode_index / contracts;
  const auto perm = deal_permutation(seed, contracts, block);
  return {perm[static_cast<std::size_t>(episode_index % contracts)], block};
}

std::uint64_t adapter_episode_seed(std::uint64_t seed, std::int64_t contract_episode) noexcept {
  constexpr std::uint64_t kAdapterDomain = 0x61646170746572ull;  // "adapter"
  return splitmix64(splitmix64(seed ^ kAdapterDomain) ^ static_cast<std::uint64_t>(contract_episode));
}

std::uint64_t episode_seed(std::uint64_t seed, std::int64_t contract_episode) noexcept {
  constexpr std::uint64_t kInitialStateDomain = 0x696e6974737461ull;  // "initsta"
  return splitmix64(splitmix64(splitmix64(seed) ^ kInitialStateDomain) ^ static_cast<std::uint64_t>(contract_episode));
}

}  // namespace actionshift::eval
