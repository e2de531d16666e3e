// Experiment YAML → Experiment (yaml-cpp is confined to this file)
#include "actionshift/eval/experiment_yaml.hpp"

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/sim/env.hpp"
#include "io.hpp"
#include "plan_detail.hpp"

#include <nlohmann/json.hpp>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <set>
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

}  // namespace

namespace detail {

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

}  // namespace detail

using detail::check_job_count;

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
                                               "seeds",    "episodes",    "backbone", "pool",   "rotation_mode", "profile",
                                               "horizon"};
  std::set<std::string> seen_keys;  // yaml-cpp keeps both entries of a repeated key and reads the first
  for (const auto& kv : root) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
    if (!known.count(key))
      throw InputError(at_line(source, kv.first), key,
                       "unknown key (expected one of name, description, tasks, splits, methods, seeds, episodes, "
                       "backbone, pool, rotation_mode, profile, horizon)");
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
  if (root["horizon"]) {
    const auto h = as_int(root["horizon"]);
    if (!h) throw InputError(at_line(source, root["horizon"]), "horizon", "expected an integer number of control steps (got " + yaml_text(root["horizon"]) + ")");
    sim::check_horizon(*h, at_line(source, root["horizon"]));
    ex.horizon = static_cast<int>(*h);
  }
  return ex;
}

Experiment load_experiment(const std::string& path) {
  // an oversized file is refused before it is read
  return parse_experiment(detail::read_file(path, "an experiment file", kMaxExperimentBytes), path);
}

}  // namespace actionshift::eval
