#include "actionshift/data/builtin_manifests.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/validate.hpp"

#include <algorithm>
#include <filesystem>
#include <utility>

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
  std::string known;
  for (const auto& n : builtin_manifest_names()) known += (known.empty() ? "" : ", ") + n;
  throw InputError(name_or_path, "", "no such manifest file and not a built-in name (built-in: " + known + ")");
}

}  // namespace actionshift::data
