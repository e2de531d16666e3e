#pragma once
/// \file
/// Scripted experts: state-feedback controllers that read only the task's state observation (by
/// field name through sim::ObservationLayout) and emit canonical pd_ee_delta_pose actions.
///
/// Every expert is a function of the current observation (no hidden phase memory): the phase is
/// recovered from the state each step (finger opening, is_grasped, relative poses). That makes
/// the expert a valid DAgger teacher, since it can label any state a learner visits. The delay-aware
/// expert (delay_aware.hpp) adds memory of its own actions on top of these.
///
/// Version strings identify the behaviour; a backbone's hash is sha256(version string) so that a
/// change of behaviour changes every job id that used the expert.

#include "actionshift/policy/policy.hpp"

#include <memory>
#include <string>

namespace actionshift::policy {

/// Version of the scripted experts' behaviour (bump when any expert changes).
inline constexpr std::string_view kExpertVersion = "actionshift-expert-v3";

/// "actionshift-expert-v3/<task>": the string whose SHA-256 identifies the expert of `task`.
std::string expert_identity(sim::TaskId task);

/// The stateless expert's action for one observation of `task` (obs layout: sim::observation_layout).
/// Throws std::invalid_argument if obs has the wrong size.
Action expert_action(sim::TaskId task, const Eigen::Ref<const Eigen::VectorXd>& obs);

/// The scripted expert of a task as a Policy (name "expert").
std::unique_ptr<Policy> make_expert(sim::TaskId task);

}  // namespace actionshift::policy
