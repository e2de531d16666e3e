#pragma once
/// \file The committed manifests (manifests/*.json), compiled into ActionShift::data.

#include "actionshift/core/manifest.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::data {

/// Names of the built-in manifests (file stems: "seen", "reference9", "full", ...), sorted.
std::vector<std::string> builtin_manifest_names();

/// The exact file text of a built-in manifest, or nullopt.
std::optional<std::string_view> builtin_manifest_text(std::string_view name);

/// Resolves a split or pool: an existing file path is loaded from disk and its stored hashes are
/// verified (record_hashes, manifest_hash, pool_hash: a failure is InputError(path, check name, …));
/// otherwise a built-in name. Throws InputError naming the argument and listing the built-in names if neither.
Manifest resolve_manifest(const std::string& name_or_path);

/// The exact text of the committed response calibration of a task on a simulator fidelity profile
/// (configs/calibration/<profile>/<task>.json), or nullopt if this build has none for them.
std::optional<std::string_view> builtin_calibration_text(std::string_view task, std::string_view profile = "maniskill");
/// The self-test's committed calibration (configs/calibration/<profile>/selftest/<task>.json: walks
/// that never cross an episode reset, the noise a probing self-test sees), or nullopt.
std::optional<std::string_view> builtin_selftest_calibration_text(std::string_view task, std::string_view profile = "maniskill");
/// The self-test's misspecification threshold for `task` on the simulator, measured by
/// `selftest --sim --calibrate-misspec` (configs/selftest/sim_misspec.json) for wirings of
/// `target_class` "delta" or "absolute"; nullopt if none was measured. InputError if the entry is malformed.
std::optional<double> builtin_selftest_misspec_ratio(std::string_view task, std::string_view target_class);
/// Built-in calibrations as "<profile>/<task>" (and "<profile>/selftest/<task>"), sorted.
std::vector<std::string> builtin_calibration_tasks();

}  // namespace actionshift::data
