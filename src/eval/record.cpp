#include "actionshift/eval/record.hpp"

#include "actionshift/sim/env.hpp"

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/sim/task.hpp"
#include "io.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>

#include <cmath>
#include <set>

namespace actionshift::eval {

namespace {

using nlohmann::json;

const std::set<std::string>& record_keys() {
  static const std::set<std::string> keys = {
      "backbone",       "backbone_sha256", "contract_index",     "contract_sha256", "episode_index",
      "job_id",         "method",          "method_variant",     "probe_displacement", "probe_steps",     "profile",    "return", "obs_noise",
      "safety_flags",   "schema_version",  "seed",               "split",           "steps",
      "success_at_end", "success_once",    "task",               "provenance"};
  return keys;
}

std::string shown(const json& v) { return " (got " + json_for_message(v, 60) + ")"; }

const json& require(const json& j, const char* key, const std::string& src) {
  const auto it = j.find(key);
  if (it == j.end()) throw InputError(src, key, "missing field");
  return *it;
}

std::string get_string(const json& j, const char* key, const std::string& src) {
  const json& v = require(j, key, src);
  if (!v.is_string()) throw InputError(src, key, "expected a string" + shown(v));
  return v.get<std::string>();
}

bool get_bool(const json& j, const char* key, const std::string& src) {
  const json& v = require(j, key, src);
  if (!v.is_boolean()) throw InputError(src, key, "expected true or false" + shown(v));
  return v.get<bool>();
}

std::int64_t get_count(const json& j, const char* key, const std::string& src) {
  const json& v = require(j, key, src);
  if (v.is_number_unsigned() && v.get<std::uint64_t>() <= static_cast<std::uint64_t>(INT64_MAX))
    return static_cast<std::int64_t>(v.get<std::uint64_t>());
  throw InputError(src, key, "expected a non-negative integer" + shown(v));
}

std::uint64_t get_u64(const json& j, const char* key, const std::string& src) {
  const json& v = require(j, key, src);
  if (v.is_number_unsigned()) return v.get<std::uint64_t>();
  throw InputError(src, key, "expected a non-negative integer" + shown(v));
}

double get_number(const json& j, const char* key, const std::string& src) {
  const json& v = require(j, key, src);
  if (!v.is_number()) throw InputError(src, key, "expected a number" + shown(v));
  return v.get<double>();
}

}  // namespace

void validate_record(const EpisodeRecord& r, const std::string& src) {
  if (r.schema_version != kRecordSchemaVersion)
    throw InputError(src, "schema_version", "unsupported schema version (got " + quote_input(r.schema_version, '"') + ", expected \"" + std::string(kRecordSchemaVersion) + "\")");
  if (!is_sha256_hex(r.job_id)) throw InputError(src, "job_id", "expected 64 lowercase hex digits (got " + quote_input(r.job_id, '"') + ")");
  if (!detail::is_token(r.task)) throw InputError(src, "task", "expected a name of [a-z0-9_.-] (got " + quote_input(r.task, '"') + ")");
  try {
    (void)sim::parse_task(r.task);  // summaries and gates group by task: a misspelt one would be a cell of its own
  } catch (const std::invalid_argument&) {
    throw InputError(src, "task", "not a task of this benchmark (got " + quote_input(r.task, '"') + ")");
  }
  (void)parse_profile(r.profile, src, "profile");
  if (!detail::is_token(r.split)) throw InputError(src, "split", "expected a name of [a-z0-9_.-] (got " + quote_input(r.split, '"') + ")");
  // a user method in another process is named by its command, `external:<command>` (docs/methods.md)
  const bool external = r.method.starts_with("external:") && r.method.size() > 9 && r.method.size() <= 512 &&
                        std::none_of(r.method.begin(), r.method.end(),
                                     [](char c) { return c == '{' || c == '}' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
  if (!external && !detail::is_token(r.method))
    throw InputError(src, "method", "expected a name of [a-z0-9_.-] or external:<command> (got " + quote_input(r.method, '"') + ")");
  if (r.method_variant.empty() || r.method_variant.size() > 512)
    throw InputError(src, "method_variant", "must be a label of 1 to 512 characters");
  for (char c : r.method_variant)
    if (static_cast<unsigned char>(c) < 0x20) throw InputError(src, "method_variant", "contains a control character");
  if (r.method_variant.compare(0, r.method.size(), r.method) != 0 ||
      (r.method_variant.size() > r.method.size() && r.method_variant[r.method.size()] != '{'))
    throw InputError(src, "method_variant",
                     "must be the method's name, or its name followed by {...} (got " + quote_input(r.method_variant, '"') + " for method " +
                         quote_input(r.method, '"') + ")");
  if (r.contract_index < 0) throw InputError(src, "contract_index", "must be >= 0");
  if (!is_sha256_hex(r.contract_sha256))
    throw InputError(src, "contract_sha256", "expected 64 lowercase hex digits (got " + quote_input(r.contract_sha256, '"') + ")");
  if (r.episode_index < 0) throw InputError(src, "episode_index", "must be >= 0");
  if (!std::isfinite(r.task_return)) throw InputError(src, "return", "must be finite");
  if (r.steps < 0) throw InputError(src, "steps", "must be >= 0");
  if (r.probe_steps < 0) throw InputError(src, "probe_steps", "must be >= 0");
  if (r.probe_steps > r.steps)
    throw InputError(src, "probe_steps", "exceeds steps (" + std::to_string(r.probe_steps) + " > " +
                                             std::to_string(r.steps) + ")");
  if (!std::isfinite(r.probe_displacement) || r.probe_displacement < 0.0)
    throw InputError(src, "probe_displacement", "must be finite and >= 0");
  if (!std::isfinite(r.obs_noise) || r.obs_noise < 0.0) throw InputError(src, "obs_noise", "must be finite and >= 0");
  std::set<std::string> seen;
  for (const auto& f : r.safety_flags) {
    const auto flag = sim::kSafetyFlags.find(f);  // the simulator's flags, "none" excepted: no flag fired is []
    if (!flag || *flag == sim::SafetyFlag::kNone) {
      std::string valid;
      for (const auto& e : sim::kSafetyFlags.entries)
        if (e.value != sim::SafetyFlag::kNone) valid += (valid.empty() ? "" : ", ") + std::string(e.name);
      throw InputError(src, "safety_flags", "unknown safety flag " + quote_input(f) + " (valid: " + valid + ")");
    }
    if (!seen.insert(f).second) throw InputError(src, "safety_flags", "duplicate flag " + quote_input(f, '"'));
  }
  if (r.backbone.empty()) throw InputError(src, "backbone", "must not be empty");
  for (char c : r.backbone)
    if (static_cast<unsigned char>(c) < 0x20) throw InputError(src, "backbone", "contains a control character");
  if (!is_sha256_hex(r.backbone_sha256))
    throw InputError(src, "backbone_sha256", "expected 64 lowercase hex digits (got " + quote_input(r.backbone_sha256, '"') + ")");
}

nlohmann::json to_json(const EpisodeRecord& r) {
  json j = json::object();
  j["schema_version"] = r.schema_version;
  j["job_id"] = r.job_id;
  j["task"] = r.task;
  j["split"] = r.split;
  j["method"] = r.method;
  j["method_variant"] = r.method_variant;
  j["seed"] = r.seed;
  j["contract_index"] = r.contract_index;
  j["contract_sha256"] = r.contract_sha256;
  j["episode_index"] = r.episode_index;
  j["success_once"] = r.success_once;
  j["success_at_end"] = r.success_at_end;
  j["return"] = r.task_return;
  j["steps"] = r.steps;
  j["probe_steps"] = r.probe_steps;
  j["probe_displacement"] = r.probe_displacement;
  j["safety_flags"] = r.safety_flags;
  j["backbone"] = r.backbone;
  j["backbone_sha256"] = r.backbone_sha256;
  j["profile"] = r.profile;
  if (r.obs_noise != 0.0) j["obs_noise"] = r.obs_noise;  // optional: only for a noisy environment
  if (!r.actionshift_version.empty())
    j["provenance"] = {{"actionshift_version", r.actionshift_version},
                       {"git_commit", r.git_commit.empty() ? json(nullptr) : json(r.git_commit)}};
  return j;
}

std::string to_jsonl_line(const EpisodeRecord& r) {
  validate_record(r);
  return canonical_dump(to_json(r));
}

EpisodeRecord record_from_json(const nlohmann::json& j, const std::string& src) {
  if (!j.is_object()) throw InputError(src, "", "expected a JSON object per line" + shown(j));
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!record_keys().count(it.key())) throw InputError(src, it.key(), "unknown field");
  EpisodeRecord r;
  r.schema_version = get_string(j, "schema_version", src);
  if (r.schema_version.size() > 1 && r.schema_version.compare(0, 2, "1.") == 0)
    throw InputError(src, "schema_version",
                     "is " + quote_input(r.schema_version, '"') +
                         ": written before paired initial states and method variants (schema 2.0); its episodes were dealt and "
                         "seeded differently and its entropy_probes/dualabi ran another rule, so it cannot be mixed with "
                         "today's records: re-run the job");
  r.job_id = get_string(j, "job_id", src);
  r.task = get_string(j, "task", src);
  r.split = get_string(j, "split", src);
  r.method = get_string(j, "method", src);
  r.method_variant = get_string(j, "method_variant", src);
  r.seed = get_u64(j, "seed", src);
  r.contract_index = get_count(j, "contract_index", src);
  r.contract_sha256 = get_string(j, "contract_sha256", src);
  r.episode_index = get_count(j, "episode_index", src);
  r.success_once = get_bool(j, "success_once", src);
  r.success_at_end = get_bool(j, "success_at_end", src);
  r.task_return = get_number(j, "return", src);
  r.steps = get_count(j, "steps", src);
  r.probe_steps = get_count(j, "probe_steps", src);
  r.probe_displacement = get_number(j, "probe_displacement", src);
  const json& flags = require(j, "safety_flags", src);
  if (!flags.is_array()) throw InputError(src, "safety_flags", "expected a list of names" + shown(flags));
  for (const auto& f : flags) {
    if (!f.is_string()) throw InputError(src, "safety_flags", "expected a list of names" + shown(flags));
    r.safety_flags.push_back(f.get<std::string>());
  }
  r.backbone = get_string(j, "backbone", src);
  r.backbone_sha256 = get_string(j, "backbone_sha256", src);
  r.profile = get_string(j, "profile", src);
  if (j.contains("obs_noise")) r.obs_noise = get_number(j, "obs_noise", src);
  if (j.contains("provenance")) {  // optional: absent in records written before it existed
    const json& p = j.at("provenance");
    if (!p.is_object() || !p.contains("actionshift_version") || !p.at("actionshift_version").is_string() ||
        !p.contains("git_commit") || !(p.at("git_commit").is_string() || p.at("git_commit").is_null()) || p.size() != 2)
      throw InputError(src, "provenance", "expected {\"actionshift_version\": string, \"git_commit\": string or null}" + shown(p));
    r.actionshift_version = p.at("actionshift_version").get<std::string>();
    if (r.actionshift_version.empty()) throw InputError(src, "provenance.actionshift_version", "must not be empty");
    if (p.at("git_commit").is_string()) r.git_commit = p.at("git_commit").get<std::string>();
  }
  validate_record(r, src);
  return r;
}

EpisodeRecord parse_record_line(std::string_view line, const std::string& src) {
  return record_from_json(parse_json_input(line, src), src);
}

RecordFile read_record_file(const std::string& path, bool allow_torn_tail) {
  const std::string bytes = detail::read_file(path, "a results file");
  RecordFile out;
  std::size_t start = 0;
  std::int64_t line_no = 0;
  while (start < bytes.size()) {
    ++line_no;
    const std::size_t nl = bytes.find('\n', start);
    const std::string src = path + ":" + std::to_string(line_no);
    if (nl == std::string::npos) {
      if (!allow_torn_tail) throw InputError(src, "", "unterminated last line (torn write?)");
      out.torn_tail = true;
      break;
    }
    out.records.push_back(parse_record_line(std::string_view(bytes).substr(start, nl - start), src));
    start = nl + 1;
  }
  return out;
}

}  // namespace actionshift::eval
