#include "actionshift/data/builtin_manifests.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/validate.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <utility>

namespace actionshift::embedded {
extern const std::string_view selftest_sim_misspec;  // configs/selftest/sim_misspec.json
}

namespace actionshift::data {
namespace detail {
extern const std::pair<std::string_view, const std::string_view*> kBuiltinManifests[];
extern const int kBuiltinManifestCount;
extern const std::pair<std::string_view, const std::string_view*> kBuiltinCalibrations[];
extern const int kBuiltinCalibrationCount;
}  // namespace detail

std::optional<std::string_view> builtin_calibration_text(std::string_view task, std::string_view profile) {
  std::string key(profile);
  key += '/';
  key += task;
  for (int i = 0; i < detail::kBuiltinCalibrationCount; ++i)
    if (detail::kBuiltinCalibrations[i].first == key) return *detail::kBuiltinCalibrations[i].second;
  return std::nullopt;
}

std::optional<std::string_view> builtin_selftest_calibration_text(std::string_view task, std::string_view profile) {
  return builtin_calibration_text(std::string("selftest/") + std::string(task), profile);
}

std::optional<double> builtin_selftest_misspec_ratio(std::string_view task, std::string_view target_class) {
  const std::string src = "configs/selftest/sim_misspec.json";
  const nlohmann::json all = parse_json_input(embedded::selftest_sim_misspec, src);
  const std::string t(task), c(target_class);
  if (!all.is_object() || !all.contains(t) || !all.at(t).is_object() || !all.at(t).contains(c)) return std::nullopt;
  const std::string field = t + "." + c + ".misspec_ratio";
  const nlohmann::json& entry = all.at(t).at(c);
  if (!entry.is_object() || !entry.contains("misspec_ratio") || !entry.at("misspec_ratio").is_number())
    throw InputError(src, field, "missing or not a number");
  const double r = entry.at("misspec_ratio").get<double>();
  if (!(r > 0.0) || !std::isfinite(r)) throw InputError(src, field, "must be finite and positive");
  return r;
}

std::vector<std::string> builtin_calibration_tasks() {
  std::vector<std::string> names;
  for (int i = 0; i < detail::kBuiltinCalibrationCount; ++i) names.emplace_back(detail::kBuiltinCalibrations[i].first);
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> builtin_manifest_names() {
  std::vector<std::string> names;
  for (int i = 0; i < detail::kBuiltinManifestCount; ++i) names.emplace_back(detail::kBuiltinManifests[i].first);
  std::sort(names.begin(), names.end());
  return names;
}

std::optional<std::string_view> builtin_manifest_text(std::string_view name) {
  for (int i = 0; i < detail::kBuiltinManifestCount; ++i)
    if (detail::kBuiltinManifests[i].first == name) return *detail::kBuiltinManifests[i].second;
  return std::nullopt;
}

Manifest resolve_manifest(const std::string& name_or_path) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(name_or_path, ec)) {
    // a file's stored hashes are verified before it is used: they enter job ids, so an edited copy
    // must never pass for the manifest it was copied from
    Manifest m = Manifest::load(name_or_path);
    for (const Check& c : validate(m, /*regenerate=*/false))
      if (!c.ok && (c.name == "record_hashes" || c.name == "manifest_hash" || c.name == "pool_hash"))
        throw InputError(name_or_path, c.name,
                         "check failed: " + c.detail + " (edited after generation? `actionshift validate` shows every check)");
    return m;
  }
  if (auto text = builtin_manifest_text(name_or_path)) return Manifest::parse(*text, "builtin:" + name_or_path);
  // a directory, device or FIFO by that name is named as such, not as a missing file
  if (std::filesystem::exists(std::filesystem::status(name_or_path, ec))) (void)Manifest::load(name_or_path);
  std::string known;
  for (const auto& n : builtin_manifest_names()) known += (known.empty() ? "" : ", ") + n;
  throw InputError(name_or_path, "", "no such manifest file and not a built-in name (built-in: " + known + ")");
}

}  // namespace actionshift::data
