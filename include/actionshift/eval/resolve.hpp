#pragma once
/// \file Names to hashed references, the way `run` and `plan` resolve them: split and pool
/// manifests (built-in names or files), backbones, built-in response calibrations, method labels
/// and parameters, user methods. A job made from these names is bound to an episode function by
/// episode_fn.hpp.

#include "actionshift/adapt/calibration.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan_expand.hpp"

#include <optional>
#include <string>

namespace actionshift::eval {

/// Resolves split, pool, backbone and calibration names the way `run` and `plan` do:
/// split/pool: a manifest file path or a built-in name; backbone: policy::make_policy;
/// calibration: the task's built-in calibration on the job's profile
/// (configs/calibration/<profile>/<task>.json) for methods that need one. Unknown names throw InputError.
PlanResolver default_resolver();

/// The task's built-in response calibration on a fidelity profile. Throws InputError if this build has none.
adapt::ResponseCalibration builtin_calibration(const std::string& task, const std::string& profile = "maniskill");
/// The self-test's built-in calibration of a task (configs/calibration/<profile>/selftest/<task>.json:
/// random walks that never cross an episode reset, the response noise a probing self-test sees).
/// Throws InputError if this build has none.
adapt::ResponseCalibration builtin_selftest_calibration(const std::string& task, const std::string& profile = "maniskill");

/// A method as written (a name or a label such as `entropy_probes{calibrated}`, with explicit
/// parameters as JSON object text) as its base name and the label's parameters merged with the explicit
/// ones (adapt::parse_method_label, adapt::merge_method_params); not yet resolved.
MethodEntry canonical_method(const MethodEntry& m);

/// Method parameters with defaults filled in (adapt::resolve_method_params) as canonical JSON text:
/// what enters the job spec, so a changed default changes the job id. `method` may be a label.
std::string resolved_method_params(const std::string& method, const std::string& params_json = "{}");

/// The job's method variant label (adapt::method_variant_label of its resolved parameters), e.g.
/// `entropy_probes`, `entropy_probes{calibrated}`, `dualabi{tau=0.5}`: what its records and summary
/// cells carry.
std::string method_variant(const JobSpec& job);

/// A label as a user wrote it, in the canonical form records carry: `entropy_probes{calibrated_preview=true,
/// lag_aware_preview=true,entropy_tolerance=0.001,motion_tiebreak=true}` → `entropy_probes{calibrated}`,
/// `entropy_probes{budget=6}` → `entropy_probes`. A name outside the registry is returned as given.
/// Throws InputError for a malformed label or invalid parameters of a registry method.
std::string canonical_method_label(const std::string& label);

/// The job identity of the user method registered as `method` (adapt::method_plugin_identity, its
/// files hashed now), or nullopt for a built-in or unknown name.
std::optional<MethodPluginRef> method_plugin_ref(const std::string& method);

/// InputError unless the job's user method (JobSpec::method_plugin) is registered in this process with
/// the same identity; also when the job names none but `job.method` is a registered user method.
void check_method_plugin(const JobSpec& job);

}  // namespace actionshift::eval
