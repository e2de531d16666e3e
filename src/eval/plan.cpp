#include "actionshift/eval/plan.hpp"

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/store.hpp"
#include "actionshift/sim/task.hpp"
#include "io.hpp"

#include <nlohmann/json.hpp>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <vector>

namespace actionshift::eval {

namespace {

using nlohmann::json;

std::string at_line(const std::string& source, const YAML::Node& n) {
  const auto m = n.Mark();
  return m.line >= 0 ? source + ":" + std::to_string(m.line + 1) : source;
}

// a value from the file, quoted for a one-line message (control characters escaped, long text cut)
std::string shown(const std::string& s) { return quote_input(s, '"'); }

std::string yaml_text(const YAML::Node& n) {
  if (n.IsScalar()) return shown(n.Scalar());
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a mapping";
  return "null";
}

bool plain(const YAML::Node& n) { return n.Tag() == "?"; }  // unquoted scalar

std::optional<std::int64_t> as_int(const YAML::Node& n) {
  if (!n.IsScalar() || !plain(n)) return std::nullopt;
  const std::string& s = n.Scalar();
  std::int64_t v = 0;
  const auto* b = s.data();
  const auto* e = s.data() + s.size();
  if (b != e && *b == '+') ++b;
  const auto res = std::from_chars(b, e, v);
  if (res.ec != std::errc() || res.ptr != e || b == e) return std::nullopt;
  return v;
}

std::optional<double> as_float(const YAML::Node& n) {
  if (!n.IsScalar() || !plain(n)) return std::nullopt;
  const std::string& s = n.Scalar();
  double v = 0.0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (res.ec != std::errc() || res.ptr != s.data() + s.size() || s.empty() || !std::isfinite(v)) return std::nullopt;
  return v;
}

constexpr std::size_t kMaxExperimentBytes = std::size_t{1} << 20;  // an experiment file is a few hundred bytes
constexpr std::size_t kMaxParamNodes = 10000;                         // values in one method's params

// Deepest flow-collection ([ ], { }) nesting outside quotes and comments. yaml-cpp's parser recurses
// once per level, so `[[[[…` 100,000 deep would overflow the stack; this scan runs before it.
int yaml_flow_depth(std::string_view text) {
  int depth = 0, deepest = 0;
  char quote = 0;
  bool comment = false;
  char prev = '\n';
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (comment) {
      if (c == '\n') comment = false;
    } else if (quote != 0) {
      if (c == '\\' && quote == '"') ++i;
      else if (c == quote) quote = 0;
    } else if (c == '#' && (prev == ' ' || prev == '\t' || prev == '\n')) {
      comment = true;
    } else if ((c == '"' || c == '\'') && (prev == ' ' || prev == '\t' || prev == '\n' || prev == '[' || prev == '{' ||
                                           prev == ',' || prev == ':' || prev == '-')) {
      quote = c;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
    prev = c;
  }
  return deepest;
}

// YAML → JSON for method parameters (core schema: null, bool, int, float, string, lists, maps); depth
// and size are bounded (aliases can make a small file name an exponentially large tree)
json to_json_value(const YAML::Node& n, const std::string& source, const std::string& field, int depth = 0,
                   std::size_t* budget = nullptr) {
  std::size_t own_budget = kMaxParamNodes;
  if (budget == nullptr) budget = &own_budget;
  if (*budget == 0) throw InputError(at_line(source, n), field, "more than " + std::to_string(kMaxParamNodes) + " values");
  --*budget;
  if (depth >= kMaxJsonDepth)
    throw InputError(at_line(source, n), field, "nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  if (!n || n.IsNull()) return nullptr;
  if (n.IsSequence()) {
    json a = json::array();
    for (std::size_t i = 0; i < n.size(); ++i)
      a.push_back(to_json_value(n[i], source, field + "[" + std::to_string(i) + "]", depth + 1, budget));
    return a;
  }
  if (n.IsMap()) {
    json o = json::object();
    for (const auto& kv : n) {
      if (!kv.first.IsScalar()) throw InputError(at_line(source, kv.first), field, "map keys must be plain names");
      const std::string key = kv.first.Scalar();
      if (invalid_utf8_offset(key) != std::string::npos)
        throw InputError(at_line(source, kv.first), field, "map key is not valid UTF-8");
      if (o.contains(key)) throw InputError(at_line(source, kv.first), field + "." + key, "duplicate key");
      o[key] = to_json_value(kv.second, source, field + "." + key, depth + 1, budget);
    }
    return o;
  }
  const std::string& s = n.Scalar();
  if (plain(n)) {
    if (s == "true" || s == "True" || s == "TRUE") return true;
    if (s == "false" || s == "False" || s == "FALSE") return false;
    if (s == "null" || s == "Null" || s == "NULL" || s == "~") return nullptr;
    if (auto i = as_int(n)) return *i;
    if (auto f = as_float(n)) return *f;
    if (s == ".nan" || s == ".inf" || s == "-.inf" || s == ".NaN" || s == ".Inf")
      throw InputError(at_line(source, n), field, "non-finite numbers are not allowed");
  }
  // a double-quoted scalar can spell a byte sequence that is not UTF-8 ("\ud800"), which JSON cannot hold
  if (invalid_utf8_offset(s) != std::string::npos) throw InputError(at_line(source, n), field, "string is not valid UTF-8");
  return s;
}

std::string require_string(const YAML::Node& n, const std::string& source, const std::string& field) {
  if (!n.IsScalar() || n.Scalar().empty()) throw InputError(at_line(source, n), field, "expected a non-empty string (got " + yaml_text(n) + ")");
  return n.Scalar();
}

std::string require_token(const YAML::Node& n, const std::string& source, const std::string& field) {
  std::string s = require_string(n, source, field);
  if (!detail::is_token(s)) throw InputError(at_line(source, n), field, "expected a name of [a-z0-9_.-] (got " + shown(s) + ")");
  return s;
}

std::vector<std::string> require_token_list(const YAML::Node& n, const std::string& source, const std::string& field) {
  if (!n.IsSequence() || n.size() == 0) throw InputError(at_line(source, n), field, "expected a non-empty list of names");
  std::vector<std::string> out;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "]";
    std::string s = require_token(n[i], source, f);
    if (!seen.insert(s).second) throw InputError(at_line(source, n[i]), f, "duplicate entry " + shown(s));
    out.push_back(std::move(s));
  }
  return out;
}

void check_json_keys(const json& j, const std::set<std::string>& keys, const std::string& src, const std::string& field) {
  if (!j.is_object()) throw InputError(src, field, "expected an object");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!keys.count(it.key())) throw InputError(src, field.empty() ? it.key() : field + "." + it.key(), "unknown field");
  for (const auto& k : keys)
    if (!j.contains(k)) throw InputError(src, field.empty() ? k : field + "." + k, "missing field");
}

// refuses an experiment whose grid exceeds kMaxPlanJobs, from the list sizes alone
void check_job_count(const Experiment& ex) {
  const std::uint64_t n = experiment_job_count(ex);
  if (n <= kMaxPlanJobs) return;
  const std::string count = n == UINT64_MAX ? "more than 2^64" : std::to_string(n);
  throw InputError(ex.source, "",
                   "the experiment expands to " + count + " jobs (" + std::to_string(ex.tasks.size()) + " tasks x " +
                       std::to_string(ex.splits.size()) + " splits x " + std::to_string(ex.methods.size()) + " methods x " +
                       std::to_string(ex.seeds.size()) + " seeds), at most " + std::to_string(kMaxPlanJobs) +
                       " in one plan (split it into several experiments)");
}

}  // namespace

std::uint64_t experiment_job_count(const Experiment& ex) {
  std::uint64_t n = 1;
  for (const std::size_t k : {ex.tasks.size(), ex.splits.size(), ex.methods.size(), ex.seeds.size()}) {
    if (k != 0 && n > UINT64_MAX / k) return UINT64_MAX;
    n *= k;
  }
  return n;
}

Experiment parse_experiment(std::string_view text, const std::string& source) {
  if (text.size() > kMaxExperimentBytes)
    throw InputError(source, "", "experiment file too large (" + std::to_string(text.size()) + " bytes, at most " +
                                     std::to_string(kMaxExperimentBytes) + ")");
  if (yaml_flow_depth(text) > kMaxJsonDepth)
    throw InputError(source, "", "malformed YAML: [ ] / { } nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  // YAML text is Unicode; ActionShift reads it as UTF-8 only (its values become JSON, which must be UTF-8)
  if (const auto bad = invalid_utf8_offset(text); bad != std::string_view::npos) {
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(bad), '\n');
    throw InputError(source + ":" + std::to_string(line), "", "not valid UTF-8 (byte offset " + std::to_string(bad) + ")");
  }
  YAML::Node root;
  std::vector<YAML::Node> docs;
  try {
    // every document is parsed: a second one (after `---`) would otherwise be silently ignored
    docs = YAML::LoadAll(std::string(text));
  } catch (const YAML::DeepRecursion& e) {
    // yaml-cpp 0.7 gives this exception the message "bad file"
    const std::string where = e.mark.line >= 0 ? source + ":" + std::to_string(e.mark.line + 1) : source;
    throw InputError(where, "", "malformed YAML: nested too deeply (yaml-cpp stops at recursion depth " + std::to_string(e.depth()) +
                                    "; an experiment needs a few levels)");
  } catch (const YAML::Exception& e) {
    const std::string where = e.mark.line >= 0 ? source + ":" + std::to_string(e.mark.line + 1) : source;
    throw InputError(where, "", "malformed YAML: " + e.msg);
  } catch (const std::exception& e) {
    throw InputError(source, "", std::string("malformed YAML: ") + e.what());
  }
  if (docs.size() > 1) {
    const auto mark = docs[1].Mark();
    const std::string where = mark.line >= 0 ? source + ":" + std::to_string(mark.line + 1) : source;
    throw InputError(where, "", "more than one YAML document (an experiment file holds one; remove the second `---` and what follows)");
  }
  if (!docs.empty()) root = docs.front();
  if (!root.IsMap()) throw InputError(source, "", "expected a mapping of experiment keys at the top level");
  static const std::set<std::string> known = {"name",     "description", "tasks",    "splits", "methods",
                                               "seeds",    "episodes",    "backbone", "pool",   "rotation_mode", "profile"};
  std::set<std::string> seen_keys;  // yaml-cpp keeps both entries of a repeated key and reads the first
  for (const auto& kv : root) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
    if (!known.count(key))
      throw InputError(at_line(source, kv.first), key,
                       "unknown key (expected one of name, description, tasks, splits, methods, seeds, episodes, "
                       "backbone, pool, rotation_mode, profile)");
    if (!seen_keys.insert(key).second) throw InputError(at_line(source, kv.first), key, "duplicate key");
  }
  for (const char* key : {"name", "tasks", "splits", "methods", "seeds", "episodes", "backbone"})
    if (!root[key]) throw InputError(source, key, "missing required key");

  Experiment ex;
  ex.source = source;
  ex.source_sha256 = sha256_hex(text);
  ex.name = require_token(root["name"], source, "name");
  if (root["description"]) ex.description = require_string(root["description"], source, "description");
  ex.tasks = require_token_list(root["tasks"], source, "tasks");
  ex.splits = require_token_list(root["splits"], source, "splits");

  const YAML::Node methods = root["methods"];
  if (!methods.IsSequence() || methods.size() == 0)
    throw InputError(at_line(source, methods), "methods", "expected a non-empty list of methods");
  std::set<std::string> seen_methods;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const std::string f = "methods[" + std::to_string(i) + "]";
    const YAML::Node m = methods[i];
    MethodEntry entry;
    if (m.IsScalar()) {
      entry.name = require_string(m, source, f);  // a name or a label, e.g. entropy_probes{calibrated}
    } else if (m.IsMap()) {
      std::set<std::string> entry_keys;
      for (const auto& kv : m) {
        const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
        if (key != "name" && key != "params" && key != "rung" && key != "version" && key != "files")
          throw InputError(at_line(source, kv.first), f + "." + key, "unknown key (expected name, params; rung, version, files for external:<command>)");
        if (!entry_keys.insert(key).second) throw InputError(at_line(source, kv.first), f + "." + key, "duplicate key");
      }
      if (!m["name"]) throw InputError(at_line(source, m), f + ".name", "missing required key");
      entry.name = require_string(m["name"], source, f + ".name");
      if (m["params"] && !m["params"].IsNull()) {
        if (!m["params"].IsMap()) throw InputError(at_line(source, m["params"]), f + ".params", "expected a mapping");
        entry.params = canonical_dump(to_json_value(m["params"], source, f + ".params"));
      }
      if ((m["rung"] || m["version"] || m["files"]) && !entry.name.starts_with("external:"))
        throw InputError(at_line(source, m), f, "rung, version and files apply to an external:<command> method only");
      if (m["rung"]) entry.rung = require_string(m["rung"], source, f + ".rung");
      if (m["version"]) entry.version = require_string(m["version"], source, f + ".version");
      if (m["files"]) {
        if (!m["files"].IsSequence()) throw InputError(at_line(source, m["files"]), f + ".files", "expected a list of paths");
        const auto dir = std::filesystem::path(source).parent_path();
        for (std::size_t k = 0; k < m["files"].size(); ++k) {
          const std::filesystem::path file = require_string(m["files"][k], source, f + ".files[" + std::to_string(k) + "]");
          entry.files.push_back((file.is_absolute() ? file : dir / file).lexically_normal().string());
        }
      }
    } else {
      throw InputError(at_line(source, m), f, "expected a method name or {name, params}");
    }
    // two entries of one method must differ in parameters, or they are the same jobs
    if (!seen_methods.insert(entry.name + entry.params).second)
      throw InputError(at_line(source, m), f, "duplicate method " + shown(entry.name));
    ex.methods.push_back(std::move(entry));
  }

  const YAML::Node seeds = root["seeds"];
  if (!seeds.IsSequence() || seeds.size() == 0) throw InputError(at_line(source, seeds), "seeds", "expected a non-empty list of integers");
  std::set<std::uint64_t> seen_seeds;
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    const std::string f = "seeds[" + std::to_string(i) + "]";
    const auto v = as_int(seeds[i]);
    if (!v || *v < 0) throw InputError(at_line(source, seeds[i]), f, "expected a non-negative integer (got " + yaml_text(seeds[i]) + ")");
    if (!seen_seeds.insert(static_cast<std::uint64_t>(*v)).second)
      throw InputError(at_line(source, seeds[i]), f, "duplicate seed " + std::to_string(*v));
    ex.seeds.push_back(static_cast<std::uint64_t>(*v));
  }
  const auto episodes = as_int(root["episodes"]);
  if (!episodes || *episodes <= 0)
    throw InputError(at_line(source, root["episodes"]), "episodes", "expected a positive integer (got " + yaml_text(root["episodes"]) + ")");
  ex.episodes = *episodes;
  ex.backbone = require_string(root["backbone"], source, "backbone");
  if (root["pool"] && root["pool"].IsMap()) {
    for (const auto& kv : root["pool"]) {
      if (!kv.first.IsScalar()) throw InputError(at_line(source, kv.first), "pool", "keys must be split names");
      const std::string split = kv.first.Scalar();
      if (std::find(ex.splits.begin(), ex.splits.end(), split) == ex.splits.end())
        throw InputError(at_line(source, kv.first), "pool." + split, "names a split that is not in splits");
      ex.split_pools[split] = kv.second.IsNull() ? std::nullopt
                                                 : std::optional<std::string>(require_token(kv.second, source, "pool." + split));
    }
    for (const auto& split : ex.splits)
      if (!ex.split_pools.count(split))
        throw InputError(at_line(source, root["pool"]), "pool." + split, "missing (a per-split pool map must name every split)");
  } else if (root["pool"] && !root["pool"].IsNull()) {
    ex.pool = require_token(root["pool"], source, "pool");
  }
  check_job_count(ex);
  if (root["rotation_mode"]) {
    ex.rotation_mode = require_string(root["rotation_mode"], source, "rotation_mode");
    (void)parse_rotation_mode(ex.rotation_mode, at_line(source, root["rotation_mode"]), "rotation_mode");
  }
  if (root["profile"]) {
    ex.profile = require_string(root["profile"], source, "profile");
    (void)parse_profile(ex.profile, at_line(source, root["profile"]), "profile");
  }
  return ex;
}

Experiment load_experiment(const std::string& path) {
  // an oversized file is refused before it is read
  return parse_experiment(detail::read_file(path, "an experiment file", kMaxExperimentBytes), path);
}

JobSpec resolve_job(const JobRequest& q, const PlanResolver& resolver) {
  if (!resolver.split || !resolver.backbone) throw std::invalid_argument("resolve_job: resolver needs split and backbone");
  if (q.pool && !resolver.pool) throw InputError(q.source, "pool", "pools cannot be resolved here");
  const MethodEntry method = resolver.canonical_method ? resolver.canonical_method(q.method) : q.method;
  if (resolver.check_method) resolver.check_method(method);
  JobSpec job;
  job.task = q.task;
  job.split = resolver.split(q.task, q.split);
  job.method = method.name;
  job.method_params = resolver.method_params ? resolver.method_params(method) : method.params;
  if (resolver.method_plugin) job.method_plugin = resolver.method_plugin(method);
  job.backbone = resolver.backbone(q.task, q.backbone);
  if (q.pool && (!resolver.method_uses_pool || resolver.method_uses_pool(method))) job.pool = resolver.pool(*q.pool);
  job.calibration_sha256 = resolver.calibration ? resolver.calibration(q.task, method, q.profile) : std::nullopt;
  job.rotation_mode = q.rotation_mode;
  job.profile = q.profile;
  job.seed = q.seed;
  job.episodes = q.episodes;
  job.obs_noise = q.obs_noise;
  validate_job(job, q.source);
  return job;
}

namespace {

// `f()`, with a failure re-thrown as the experiment file's error at `field` (a resolver knows the
// name it was given, not which line of which file named it)
template <class F>
auto in_experiment(const Experiment& ex, const std::string& field, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    if (e.source() == ex.source) throw;
    throw InputError(ex.source, field, e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(ex.source, field, e.what());
  }
}

}  // namespace

Plan make_plan(const Experiment& ex, const PlanResolver& resolver) {
  if (!resolver.split || !resolver.backbone) throw std::invalid_argument("make_plan: resolver needs split and backbone");
  if (ex.pool && !resolver.pool) throw InputError(ex.source, "pool", "pools cannot be resolved here");
  check_job_count(ex);  // before anything is resolved or expanded
  Plan plan;
  plan.experiment = ex.name;
  plan.source = ex.source;
  plan.source_sha256 = ex.source_sha256;
  std::map<std::string, std::optional<PoolRef>> pools;  // by split
  for (const auto& split_name : ex.splits) {
    const auto it = ex.split_pools.find(split_name);
    const std::optional<std::string> name = it != ex.split_pools.end() ? it->second : ex.pool;
    if (name && !resolver.pool) throw InputError(ex.source, "pool", "pools cannot be resolved here");
    const std::string field = it != ex.split_pools.end() ? "pool." + split_name : "pool";
    pools[split_name] = name ? std::optional<PoolRef>(in_experiment(ex, field, [&] { return resolver.pool(*name); })) : std::nullopt;
  }
  const auto method_field = [](std::size_t i) { return "methods[" + std::to_string(i) + "]"; };
  std::vector<MethodEntry> methods = ex.methods;
  if (resolver.canonical_method)
    for (std::size_t i = 0; i < methods.size(); ++i)
      methods[i] = in_experiment(ex, method_field(i), [&] { return resolver.canonical_method(ex.methods[i]); });
  if (resolver.check_method)
    for (std::size_t i = 0; i < methods.size(); ++i)
      in_experiment(ex, method_field(i), [&] { resolver.check_method(methods[i]); });
  std::set<std::string> ids;
  for (std::size_t t = 0; t < ex.tasks.size(); ++t) {
    const std::string& task = ex.tasks[t];
    const std::string task_field = "tasks[" + std::to_string(t) + "]";
    in_experiment(ex, task_field, [&] { (void)sim::parse_task(task); });
    const BackboneRef backbone =
        in_experiment(ex, "backbone", [&] { return resolver.backbone(task, ex.backbone); });
    for (std::size_t s = 0; s < ex.splits.size(); ++s) {
      const std::string& split_name = ex.splits[s];
      const SplitRef split =
          in_experiment(ex, "splits[" + std::to_string(s) + "]", [&] { return resolver.split(task, split_name); });
      for (std::size_t m = 0; m < methods.size(); ++m) {
        const MethodEntry& method = methods[m];
        const std::optional<std::string> calibration =
            resolver.calibration
                ? in_experiment(ex, method_field(m), [&] { return resolver.calibration(task, method, ex.profile); })
                : std::nullopt;
        const std::string params = resolver.method_params
                                       ? in_experiment(ex, method_field(m), [&] { return resolver.method_params(method); })
                                       : method.params;
        const bool uses_pool =
            !resolver.method_uses_pool || in_experiment(ex, method_field(m), [&] { return resolver.method_uses_pool(method); });
        const std::optional<MethodPluginRef> plugin =
            resolver.method_plugin ? in_experiment(ex, method_field(m), [&] { return resolver.method_plugin(method); })
                                   : std::nullopt;
        for (const auto seed : ex.seeds) {
          PlannedJob pj;
          pj.index = static_cast<std::int64_t>(plan.jobs.size());
          pj.spec.task = task;
          pj.spec.split = split;
          pj.spec.method = method.name;
          pj.spec.method_params = params;
          pj.spec.method_plugin = plugin;
          pj.spec.backbone = backbone;
          if (uses_pool) pj.spec.pool = pools[split_name];
          pj.spec.calibration_sha256 = calibration;
          pj.spec.rotation_mode = ex.rotation_mode;
          pj.spec.profile = ex.profile;
          pj.spec.seed = seed;
          pj.spec.episodes = ex.episodes;
          in_experiment(ex, task_field, [&] { validate_job(pj.spec, ex.source); });
          pj.job_id = job_id(pj.spec);
          if (!ids.insert(pj.job_id).second)
            throw InputError(ex.source, "", "two plan entries resolve to the same job " + pj.job_id);
          plan.jobs.push_back(std::move(pj));
        }
      }
    }
  }
  return plan;
}

nlohmann::json plan_to_json(const Plan& plan) {
  json j = json::object();
  j["schema_version"] = "1.0";
  j["experiment"] = plan.experiment;
  j["source"] = plan.source;
  j["source_sha256"] = plan.source_sha256;
  j["job_count"] = plan.jobs.size();
  j["jobs"] = json::array();
  for (const auto& pj : plan.jobs)
    j["jobs"].push_back({{"index", pj.index}, {"job_id", pj.job_id}, {"spec", job_to_json(pj.spec)}});
  return j;
}

Plan plan_from_json(const nlohmann::json& j, const std::string& source) {
  check_json_keys(j, {"schema_version", "experiment", "source", "source_sha256", "job_count", "jobs"}, source, "");
  if (j.at("schema_version") != "1.0") throw InputError(source, "schema_version", "unsupported plan schema version");
  Plan plan;
  if (!j.at("experiment").is_string() || !j.at("source").is_string() || !j.at("source_sha256").is_string())
    throw InputError(source, "experiment", "experiment, source and source_sha256 must be strings");
  plan.experiment = j.at("experiment").get<std::string>();
  plan.source = j.at("source").get<std::string>();
  plan.source_sha256 = j.at("source_sha256").get<std::string>();
  const json& jobs = j.at("jobs");
  if (!jobs.is_array()) throw InputError(source, "jobs", "expected a list");
  if (jobs.size() > kMaxPlanJobs)
    throw InputError(source, "jobs", std::to_string(jobs.size()) + " jobs, at most " + std::to_string(kMaxPlanJobs) + " in one plan");
  if (!j.at("job_count").is_number_integer() || j.at("job_count").get<std::int64_t>() != static_cast<std::int64_t>(jobs.size()))
    throw InputError(source, "job_count", "does not match the number of jobs (" + std::to_string(jobs.size()) + ")");
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const std::string f = "jobs[" + std::to_string(i) + "]";
    check_json_keys(jobs[i], {"index", "job_id", "spec"}, source, f);
    PlannedJob pj;
    const json& index = jobs[i].at("index");
    if (!index.is_number_integer() || index.get<std::int64_t>() != static_cast<std::int64_t>(i))
      throw InputError(source, f + ".index", "expected " + std::to_string(i));
    pj.index = static_cast<std::int64_t>(i);
    pj.spec = job_from_json(jobs[i].at("spec"), source + ": " + f + ".spec");
    pj.job_id = job_id(pj.spec);
    if (jobs[i].at("job_id") != pj.job_id)
      throw InputError(source, f + ".job_id", "does not match the hash of its spec (expected " + pj.job_id + ")");
    plan.jobs.push_back(std::move(pj));
  }
  return plan;
}

Plan load_plan(const std::string& path) {
  const std::string text = detail::read_file(path, "a plan file", kMaxInputFileBytes);
  return plan_from_json(parse_json_input(text, path), path);
}

void write_plan(const std::string& path, const Plan& plan) { write_json_atomic(path, plan_to_json(plan)); }

std::string shell_quote(std::string_view s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "'\\''";
    else out.push_back(c);
  }
  out += "'";
  return out;
}

namespace {

void require_slurm_plan(const Plan& plan, const SlurmOptions& o, const char* what) {
  if (plan.jobs.empty()) throw std::invalid_argument(std::string(what) + ": the plan has no jobs");
  if (o.plan_path.empty()) throw std::invalid_argument(std::string(what) + ": plan_path is required");
  if (o.max_array_size == 0) throw std::invalid_argument(std::string(what) + ": max_array_size must be positive");
  // #SBATCH lines are read by Slurm, not the shell: quoting cannot protect them, so a line break (or any
  // control character) in a value written there would start a line of its own, run as a shell command
  const auto one_line = [](const std::string& v, const char* field) {
    for (char c : v)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
        throw InputError("plan --slurm", field, "contains a control character (got " + quote_input(v) + "); it would break the #SBATCH lines");
  };
  one_line(o.out_dir, "--out");
  one_line(o.executable, "executable");
  one_line(o.plan_path, "plan path");
  one_line(o.time_limit, "--time");
  one_line(o.mem, "--mem");
  one_line(o.partition, "--partition");
  one_line(plan.experiment, "experiment name");
}

// The #SBATCH lines every script shares: time, memory, partition.
void common_directives(std::ostream& s, const SlurmOptions& o) {
  s << "#SBATCH --time=" << o.time_limit << "\n";
  if (!o.mem.empty()) s << "#SBATCH --mem=" << o.mem << "\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
}

bool all_digits(std::string_view t) {
  return !t.empty() && std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

std::vector<SlurmChunk> slurm_chunks(std::int64_t job_count, unsigned max_array_size) {
  if (max_array_size == 0) throw std::invalid_argument("slurm_chunks: max_array_size must be positive");
  std::vector<SlurmChunk> out;
  for (std::int64_t off = 0; off < job_count; off += max_array_size)
    out.push_back({off, std::min<std::int64_t>(max_array_size, job_count - off)});
  return out;
}

std::string slurm_array_script(const Plan& plan, const SlurmOptions& o) {
  require_slurm_plan(plan, o, "slurm_array_script");
  const unsigned cpus = o.cpus_per_task ? o.cpus_per_task : 1;
  const auto n = static_cast<std::int64_t>(plan.jobs.size());
  const auto chunks = slurm_chunks(n, o.max_array_size);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Slurm array task for experiment '" << plan.experiment << "' (" << n << " jobs in " << chunks.size()
    << (chunks.size() == 1 ? " array" : " arrays") << " of at most " << o.max_array_size << " tasks).\n"
    << "# Task i of a submission runs plan job ACTIONSHIFT_JOB_OFFSET + i (offset 0 by default).\n"
    << "# Re-submitting is safe: finished jobs are no-ops and killed or pre-empted jobs resume from\n"
    << "# their last complete record.\n";
  s << "# Submit every array and the merge job with the <experiment>.submit.sh script beside this one.\n";
  s << "#SBATCH --job-name=actionshift-" << plan.experiment << "\n";
  if (chunks.size() == 1) {
    s << "#SBATCH --array=0-" << n - 1;
    if (o.max_parallel) s << "%" << o.max_parallel;
    s << "\n";
  }
  s << "#SBATCH --cpus-per-task=" << cpus << "\n";
  common_directives(s, o);
  s << "#SBATCH --output=" << o.out_dir << "/slurm-%A_%a.log\n"
    << "#SBATCH --requeue\n"
    << "set -euo pipefail\n"
    << "job_index=$(( ${ACTIONSHIFT_JOB_OFFSET:-0} + ${SLURM_ARRAY_TASK_ID:?not a Slurm array task} ))\n"
    << "exec " << shell_quote(o.executable) << " run --plan " << shell_quote(o.plan_path)
    << " --job-index \"${job_index}\" --out " << shell_quote(o.out_dir) << " --threads \"${SLURM_CPUS_PER_TASK:-" << cpus
    << "}\"\n";
  return s.str();
}

std::string slurm_merge_script(const Plan& plan, const SlurmOptions& o) {
  require_slurm_plan(plan, o, "slurm_merge_script");
  bool oracle = false, no_adapt = false;
  for (const auto& j : plan.jobs) {
    oracle = oracle || j.spec.method == "oracle";
    no_adapt = no_adapt || j.spec.method == "no_adapt";
  }
  const std::string out = shell_quote(o.out_dir);
  const std::string exe = shell_quote(o.executable);
  const std::string base = o.out_dir + "/" + plan.experiment;
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Merge job for experiment '" << plan.experiment << "': runs after every array task succeeded\n"
    << "# (--dependency=afterok). Writes " << plan.experiment << ".summary.md and " << plan.experiment
    << ".summary.json beside the results";
  if (oracle && no_adapt) s << " and the Gate 1 verdict (exit 1 if a gated cell fails)";
  s << ".\n"
    << "#SBATCH --job-name=actionshift-" << plan.experiment << "-merge\n"
    << "#SBATCH --cpus-per-task=1\n";
  common_directives(s, o);
  s << "#SBATCH --output=" << o.out_dir << "/slurm-merge-%j.log\n"
    << "set -euo pipefail\n"
    << exe << " summarize " << out << " --out " << shell_quote(base + ".summary.json") << " > "
    << shell_quote(base + ".summary.md") << "\n";
  if (oracle && no_adapt)
    s << exe << " gate1 --results " << out << " --verdict " << shell_quote(o.out_dir + "/gate1.verdict.json") << "\n";
  return s.str();
}

std::string slurm_submit_script(const Plan& plan, const SlurmOptions& o) {
  require_slurm_plan(plan, o, "slurm_submit_script");
  if (o.script_path.empty() || o.merge_script_path.empty())
    throw std::invalid_argument("slurm_submit_script: script_path and merge_script_path are required");
  const auto chunks = slurm_chunks(static_cast<std::int64_t>(plan.jobs.size()), o.max_array_size);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Submits experiment '" << plan.experiment << "': " << plan.jobs.size() << " jobs as " << chunks.size()
    << (chunks.size() == 1 ? " array" : " arrays") << " (MaxArraySize " << o.max_array_size
    << "), then the merge job once all of them succeeded.\n"
    << "# Run from any directory: bash <this file>. Prints the Slurm job ids.\n"
    << "set -euo pipefail\n"
    << "ids=()\n";
  for (const auto& c : chunks) {
    s << "ids+=(\"$(sbatch --parsable --array=0-" << c.count - 1;
    if (o.max_parallel) s << "%" << o.max_parallel;
    s << " --export=ALL,ACTIONSHIFT_JOB_OFFSET=" << c.offset << " " << shell_quote(o.script_path)
      << " | cut -d ';' -f 1)\")\n";
  }
  s << "dep=$(IFS=:; echo \"${ids[*]}\")\n"
    << "merge=$(sbatch --parsable --dependency=afterok:\"${dep}\" --kill-on-invalid-dep=yes "
    << shell_quote(o.merge_script_path) << " | cut -d ';' -f 1)\n"
    << "echo \"array jobs: ${ids[*]}\"\n"
    << "echo \"merge job: ${merge}\"\n";
  return s.str();
}

bool valid_slurm_time(std::string_view t) {
  if (t == "UNLIMITED" || t == "INFINITE" || t == "unlimited" || t == "infinite") return true;
  std::string_view days, rest = t;
  if (const auto dash = t.find('-'); dash != std::string_view::npos) {
    days = t.substr(0, dash);
    rest = t.substr(dash + 1);
    if (!all_digits(days)) return false;
  }
  std::vector<std::string_view> parts;
  std::size_t pos = 0;
  while (true) {
    const auto colon = rest.find(':', pos);
    parts.push_back(rest.substr(pos, colon == std::string_view::npos ? std::string_view::npos : colon - pos));
    if (colon == std::string_view::npos) break;
    pos = colon + 1;
  }
  if (parts.size() > 3) return false;
  // without days: M, M:S, H:M:S; with days: D-H, D-H:M, D-H:M:S
  bool nonzero = false;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (!all_digits(parts[i]) || parts[i].size() > 9) return false;
    const long v = std::stol(std::string(parts[i]));
    nonzero = nonzero || v > 0;
    const bool leading = i == 0;  // the leading field (minutes, hours or days-hours) may exceed 59
    if (!leading && v > 59) return false;
  }
  if (!days.empty()) {
    if (days.size() > 6) return false;
    nonzero = nonzero || std::stol(std::string(days)) > 0;
    if (std::stol(std::string(parts[0])) > 23) return false;
  }
  return nonzero;
}

bool valid_slurm_mem(std::string_view t) {
  if (t.empty()) return false;
  std::string_view digits = t;
  const char last = t.back();
  if (last == 'K' || last == 'M' || last == 'G' || last == 'T' || last == 'k' || last == 'm' || last == 'g' || last == 't')
    digits = t.substr(0, t.size() - 1);
  if (!all_digits(digits) || digits.size() > 12) return false;
  return std::stoll(std::string(digits)) > 0;
}

std::optional<unsigned> parse_max_array_size(std::string_view text) {
  std::size_t pos = 0;
  while (pos < text.size()) {
    auto eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    if (line.rfind("MaxArraySize", 0) != 0) continue;
    const auto eq = line.find('=');
    if (eq == std::string_view::npos) continue;
    std::string_view v = line.substr(eq + 1);
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    while (!v.empty() && (v.back() == ' ' || v.back() == '\r' || v.back() == '\t')) v.remove_suffix(1);
    if (!all_digits(v) || v.size() > 9) return std::nullopt;
    const unsigned long n = std::stoul(std::string(v));
    if (n == 0) return std::nullopt;
    return static_cast<unsigned>(n);
  }
  return std::nullopt;
}

}  // namespace actionshift::eval
