#pragma once
/// \file Binding a job spec to the real layers: names resolve to the built-in manifests, response
/// calibrations and backbones (their hashes are checked against the spec), and an episode runs the
/// backbone through the method's adapter in the hidden-contract environment.

#include "actionshift/adapt/calibration.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/policy/policy.hpp"

#include <memory>
#include <optional>
#include <string>

namespace actionshift::eval {

/// Resolves split, pool, backbone and calibration names the way `run` and `plan` do:
/// split/pool: a manifest file path or a built-in name; backbone: policy::make_policy;
/// calibration: the task's built-in calibration (configs/calibration/<task>.json) for methods that
/// need one. Unknown names throw InputError.
PlanResolver default_resolver();

/// The task's built-in response calibration. Throws InputError if this build has none.
adapt::ResponseCalibration builtin_calibration(const std::string& task);

/// Method parameters with defaults filled in (adapt::resolve_method_params) as canonical JSON text:
/// what enters the job spec, so a changed default changes the job id.
std::string resolved_method_params(const std::string& method, const std::string& params_json = "{}");

/// The episode function of `job`. Resolves every name and checks that the split manifest hash, pool
/// hash, calibration hash and backbone hash equal the spec's (a stale plan is an InputError, never
/// a silent mismatch). The function is thread-safe: each runner worker gets its own environments,
/// policy clone and adapters.
///
/// One episode: reset the hidden-contract env with the episode seed; each step the backbone's
/// canonical intent goes through adapter.encode (frame rotation from the observed TCP quaternion in
/// `live` mode, identity otherwise), the env steps the raw action, and the adapter observes the TCP
/// response. Episodes run the full horizon (success does not end them) unless a safety check fires.
EpisodeFn make_episode_fn(const JobSpec& job);

/// The same episode function with the backbone supplied by the caller instead of resolved by name
/// (e.g. a policy implemented in the host process, such as a Python callable). Its name() and
/// sha256() must equal the spec's backbone (InputError otherwise); each runner worker uses its own
/// `backbone->clone()`.
EpisodeFn make_episode_fn(const JobSpec& job, std::shared_ptr<const policy::Policy> backbone);

}  // namespace actionshift::eval
