// Names → hashed references (default_resolver), built-in calibrations, method labels and user methods
#include "actionshift/eval/resolve.hpp"

#include "actionshift/adapt/plugin.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/sim/task.hpp"
#include "resolve_detail.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

namespace actionshift::eval {

namespace detail {

Manifest manifest_of_kind(const std::string& name, bool pool) {
  Manifest m = data::resolve_manifest(name);
  if (m.is_pool() != pool)
    throw InputError(name, "kind", pool ? "is a split manifest, not a pool" : "is a pool, not a split manifest");
  return m;
}

nlohmann::json parse_params(const std::string& text, const std::string& method) {
  const nlohmann::json j = parse_json_input(text, "method " + method, "params");
  if (!j.is_object()) throw InputError("method " + method, "params", "not a JSON object");
  return j;
}

}  // namespace detail

namespace {

using detail::manifest_of_kind;
using detail::parse_params;

// The absolute path of a manifest named by a file ("" for a built-in name): recorded in the job, so
// the job is resolved from the same file wherever it runs, never by the manifest's name.
std::string manifest_file_path(const std::string& name_or_path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(name_or_path, ec)) return {};
  const std::filesystem::path abs = std::filesystem::absolute(name_or_path, ec);
  return ec ? std::string() : abs.lexically_normal().string();
}

}  // namespace

adapt::ResponseCalibration builtin_calibration(const std::string& task, const std::string& profile) {
  const auto text = data::builtin_calibration_text(task, profile);
  if (!text)
    throw InputError("calibration", task,
                     "no built-in calibration for this task on profile '" + profile + "' (run `actionshift calibrate --task " + task +
                         " --profile " + profile + "`)");
  return adapt::ResponseCalibration::from_json(std::string(*text), "builtin:calibration/" + profile + "/" + task);
}

adapt::ResponseCalibration builtin_selftest_calibration(const std::string& task, const std::string& profile) {
  const auto text = data::builtin_selftest_calibration_text(task, profile);
  if (!text)
    throw InputError("calibration", task, "no built-in self-test calibration for this task on profile '" + profile + "'");
  return adapt::ResponseCalibration::from_json(std::string(*text), "builtin:calibration/" + profile + "/selftest/" + task);
}

MethodEntry canonical_method(const MethodEntry& m) {
  const adapt::MethodLabel label = adapt::parse_method_label(m.name);
  MethodEntry out = m;  // an external method keeps its rung, version and files
  out.name = label.name;
  out.params = canonical_dump(adapt::merge_method_params(label, parse_params(m.params, label.name)));
  return out;
}

std::string resolved_method_params(const std::string& method, const std::string& params_json) {
  const MethodEntry m = canonical_method(MethodEntry{method, params_json});
  return canonical_dump(adapt::resolve_method_params(m.name, parse_params(m.params, m.name)));
}

std::string canonical_method_label(const std::string& label) {
  const MethodEntry m = canonical_method(MethodEntry{label, "{}"});
  const auto& known = adapt::method_names();
  if (std::find(known.begin(), known.end(), m.name) == known.end()) return label;  // not ours to canonicalize
  return adapt::method_variant_label(m.name, adapt::resolve_method_params(m.name, parse_params(m.params, m.name)));
}

namespace {
std::string method_variant_uncached(const JobSpec& job);
}  // namespace

std::string method_variant(const JobSpec& job) {
  // called for every record a job writes or re-reads: remember the last job's label (per thread)
  thread_local std::string last_method, last_params, last_label;
  if (job.method != last_method || job.method_params != last_params || last_label.empty()) {
    last_label = method_variant_uncached(job);
    last_method = job.method;
    last_params = job.method_params;
  }
  return last_label;
}

namespace {
std::string method_variant_uncached(const JobSpec& job) {
  const auto& known = adapt::method_names();
  const nlohmann::json params = parse_params(job.method_params, job.method);
  // a user method's label lists every parameter its job has, so it is the same whether or not the
  // method is registered in the process that reads its records
  if (!job.method_plugin && std::find(known.begin(), known.end(), job.method) != known.end())
    return adapt::method_variant_label(job.method, adapt::resolve_method_params(job.method, params));
  // a user method, or a method outside the registry (a test's stand-in): every parameter it has is part of its label
  std::string items;
  for (auto it = params.begin(); it != params.end(); ++it)
    items += (items.empty() ? "" : ",") + it.key() + "=" + (it.value().is_string() ? it.value().get<std::string>() : canonical_dump(it.value()));
  return items.empty() ? job.method : job.method + "{" + items + "}";
}
}  // namespace

std::optional<MethodPluginRef> method_plugin_ref(const std::string& method) {
  const auto id = adapt::method_plugin_identity(method);
  if (!id) return std::nullopt;
  return MethodPluginRef{id->kind, id->version, id->rung, id->sha256, id->files};
}

PlanResolver default_resolver() {
  PlanResolver r;
  r.split = [](const std::string&, const std::string& split) {
    const Manifest m = manifest_of_kind(split, false);
    return SplitRef{m.name(), m.manifest_sha256(), static_cast<std::int64_t>(m.test().size()), manifest_file_path(split)};
  };
  r.pool = [](const std::string& pool) {
    const Manifest m = manifest_of_kind(pool, true);
    return PoolRef{m.name(), m.pool_sha256(), manifest_file_path(pool)};
  };
  r.backbone = [](const std::string& task, const std::string& name) {
    // identity only: an external policy's process is started by the job, not by planning it
    const policy::BackboneIdentity b = policy::backbone_identity(name, sim::parse_task(task));
    return BackboneRef{b.name, b.sha256};
  };
  r.calibration = [](const std::string& task, const MethodEntry& m, const std::string& profile) -> std::optional<std::string> {
    if (!adapt::method_needs_calibration(m.name)) return std::nullopt;
    return builtin_calibration(task, profile).sha256();
  };
  r.canonical_method = [](const MethodEntry& m) { return canonical_method(m); };
  r.check_method = [](const MethodEntry& m) { adapt::resolve_method_params(m.name, parse_params(m.params, m.name)); };
  r.method_params = [](const MethodEntry& m) { return resolved_method_params(m.name, m.params); };
  r.method_uses_pool = [](const MethodEntry& m) { return adapt::method_needs_pool(m.name); };
  r.method_plugin = [](const MethodEntry& m) { return method_plugin_ref(m.name); };
  return r;
}

void check_method_plugin(const JobSpec& job) {
  const std::optional<MethodPluginRef> now = method_plugin_ref(job.method);
  if (!job.method_plugin) {
    if (now)
      throw InputError("job", "method.plugin",
                       "names no user method, but '" + job.method + "' is one registered here; make the job again");
    return;
  }
  const MethodPluginRef& want = *job.method_plugin;
  if (!now)
    throw InputError("job", "method.name",
                     "'" + job.method + "' is a user method (" + want.kind + ", version " + want.version +
                         ") that is not registered in this process; register it before running its job (docs/methods.md)");
  if (now->sha256 != want.sha256)
    throw InputError(want.files.empty() ? "job" : want.files.front(), "method.plugin.sha256",
                     "user method '" + job.method + "' is now version " + now->version + " (" + now->kind + ", rung " + now->rung +
                         ", content " + now->sha256.substr(0, 12) + "), the job's version " + want.version + " (" + want.kind +
                         ", rung " + want.rung + ", content " + want.sha256.substr(0, 12) + "); make the job again");
}

}  // namespace actionshift::eval
