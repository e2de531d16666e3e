#pragma once
/// \file Binding a job spec to the real layers: names resolve to the built-in manifests, response
/// calibrations and backbones (their hashes are checked against the spec), and an episode runs the
/// backbone through the method's adapter in the hidden-contract environment.

#include "actionshift/adapt/calibration.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/policy/external.hpp"
#include "actionshift/policy/policy.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace actionshift::sim {
class Env;
struct StepResult;
}  // namespace actionshift::sim

namespace actionshift::eval {

/// Run-time options of an episode function that do not change results (and so stay out of the job id).
struct EpisodeFnOptions {
  policy::ExternalOptions external;  ///< timeouts of an external:<command> backbone (run --step-timeout)
  /// The response calibration of a method that needs one, instead of the task's built-in one (run
  /// --calibration FILE, e.g. one measured under the job's observation noise). Its hash is already
  /// the job's calibration_sha256 (checked: a mismatch is an InputError), so it changes nothing the id does not name.
  std::optional<adapt::ResponseCalibration> calibration;
  std::string calibration_source{"calibration"};  ///< the file `calibration` was read from, for messages
};

/// The episode function of `job`. Resolves every name and checks that the split manifest hash, pool
/// hash, calibration hash and backbone hash equal the spec's (a stale plan is an InputError, never
/// a silent mismatch). The function is thread-safe: each runner worker gets its own environments,
/// policy clone and adapters.
///
/// One episode: reset the hidden-contract env with the episode seed; each step the backbone's
/// canonical intent goes through adapter.encode (frame rotation from the observed TCP quaternion in
/// `live` mode, identity otherwise), the env steps the raw action, and the adapter observes the TCP
/// response. Episodes run the full horizon (success does not end them) unless a safety check fires.
EpisodeFn make_episode_fn(const JobSpec& job, const EpisodeFnOptions& options = {});

/// What an episode observer is shown: the state after the reset (step 0) and after every control
/// step of the episode, in order. The pointers are valid during the call only.
struct EpisodeStepView {
  int step{0};                              ///< control steps taken so far (0: the state after reset)
  int horizon{0};                           ///< the task's horizon
  bool probe{false};                        ///< the action just taken was an adapter probe
  const sim::StepResult* result{nullptr};   ///< the environment's last result (success, safety)
  const sim::Env* env{nullptr};             ///< the unwrapped environment, read-only (for rendering)
  const Action* raw{nullptr};               ///< the raw action just sent (null at step 0): what a log records
};
/// Called once per EpisodeStepView.
using EpisodeObserver = std::function<void(const EpisodeStepView&)>;

/// Extras of an observed episode function (`actionshift render`).
struct EpisodeHooks {
  EpisodeObserver observer;                 ///< called after the reset and after each step; may be null
  /// Run this contract instead of the split's (the `--clean` render uses Contract::identity()); the
  /// record's contract_sha256 is then this contract's. Not set: the split's contract, as the runner.
  std::optional<Contract> contract_override;
};

/// The same episode function with hooks: with default hooks it is make_episode_fn(job, options), and
/// with only an observer its episodes are those of the runner, step for step.
EpisodeFn make_episode_fn(const JobSpec& job, const EpisodeFnOptions& options, EpisodeHooks hooks);
/// make_episode_fn(job, {}, hooks).
inline EpisodeFn make_episode_fn(const JobSpec& job, EpisodeHooks hooks) {
  return make_episode_fn(job, EpisodeFnOptions{}, std::move(hooks));
}

/// The same episode function with the backbone supplied by the caller instead of resolved by name
/// (e.g. a policy implemented in the host process, such as a Python callable). Its name() and
/// sha256() must equal the spec's backbone (InputError otherwise); each runner worker uses its own
/// `backbone->clone()`.
EpisodeFn make_episode_fn(const JobSpec& job, std::shared_ptr<const policy::Policy> backbone, EpisodeHooks hooks = {});
/// The same with a given response calibration (`options.calibration`, as run --calibration; the other
/// options concern a backbone resolved by name and are not used).
EpisodeFn make_episode_fn(const JobSpec& job, std::shared_ptr<const policy::Policy> backbone, const EpisodeFnOptions& options,
                          EpisodeHooks hooks = {});

}  // namespace actionshift::eval
