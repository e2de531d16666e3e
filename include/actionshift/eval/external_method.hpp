#pragma once
/// \file A user method in any language: a process speaking JSON lines (protocol
/// "actionshift-method-v1", docs/methods.md "From any language"), registered as a user method of kind
/// `external` named `external:<command>`. One process per runner worker, kept for the whole job:
///
///   -> {"type":"hello","protocol":"actionshift-method-v1","task":"pick_cube","rung":"pool",
///       "params":{},"inputs":{"pool":[contracts]|null,"calibration":{"alpha":[6],"sigma":[6],
///       "gripper_alpha":a,"gripper_sigma":s}|null,"grammar":{...}|null}}
///   <- {"type":"ready"}
///   -> {"type":"begin_episode","seed":N}                                          (no reply)
///   -> {"type":"encode","canonical":[7],"R":[9, row-major]}
///   <- {"raw":[7 finite numbers],"probe":true|false}
///   -> {"type":"observe","raw":[7],"response":[6],"R":[9],"finger_delta":x|null}   (no reply)
///
/// The inputs are exactly the declared rung's (adapt::PluginInputs); nothing names the contract,
/// the job's seed or the results directory. Timeouts and process lifetime are the external policy's
/// (policy::LineProcess).

#include "actionshift/adapt/plugin.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/policy/external.hpp"

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace actionshift::eval {

inline constexpr std::string_view kExternalMethodProtocol = "actionshift-method-v1";

/// One reply line to an encode request: {"raw": 7 finite numbers, "probe": bool (optional, false)}.
/// Throws std::invalid_argument(reason).
std::pair<Action, bool> parse_encode_reply(std::string_view reply);

/// Registers `external:<command>` as a user method of kind external: `rung` (pool, grammar or none),
/// `version`, and the files whose content enters its identity (its script, weights). The command
/// itself is part of the name, and so of the identity. Throws InputError for an empty command, one
/// holding `{`, `}` or a control character (a method label's delimiters), and as adapt::register_method.
[[nodiscard]] adapt::MethodRegistration register_external_method(const std::string& command, adapt::Rung rung,
                                                                  const std::vector<std::string>& files = {},
                                                                  const std::string& version = "0",
                                                                  policy::ExternalOptions options = {});

/// Registers the external method a job names (its method.plugin of kind external) with the job's own
/// rung, version and files, so a plan's job runs without command-line flags; nothing when the job's
/// method is not external. The job's identity is then checked as for any user method.
[[nodiscard]] adapt::MethodRegistration register_external_method_of(const JobSpec& job, policy::ExternalOptions options = {});

}  // namespace actionshift::eval
