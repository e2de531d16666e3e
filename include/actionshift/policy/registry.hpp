#pragma once
/// \file
/// Backbones by name, as used on the command line (`--backbone B`):
///   expert                 scripted expert of the task (expert.hpp)
///   expert-delay-aware     the expert with a lag estimate and Smith predictor (delay_aware.hpp)
///   mlp                    <backbones_dir>/<task>.mlp.asmlp (mlp.hpp)
///   mlp-delay-aware        <backbones_dir>/<task>.mlp-delay-aware.asmlp
///   mlp:<path>             any weight file (its task must match)
///   dp:<path>              a Diffusion Policy weight file, .asdp (dp.hpp; its task must match)
///   external:<command>     a process speaking JSON lines (external.hpp)

#include "actionshift/policy/external.hpp"
#include "actionshift/policy/policy.hpp"

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::policy {

/// Where committed MLP weights are looked up: $ACTIONSHIFT_BACKBONES_DIR if set, else the source
/// tree's configs/backbones if it exists, else the installed <datadir>/actionshift/backbones.
std::string default_backbones_dir();

/// Options of make_policy.
struct RegistryOptions {
  std::string backbones_dir;   ///< "" = default_backbones_dir()
  ExternalOptions external;    ///< timeouts of external policies
};

/// Weight file of a built-in MLP backbone for a task, e.g. "<dir>/pick_cube.mlp.asmlp".
std::string mlp_weights_path(std::string_view backbone, sim::TaskId task, const std::string& backbones_dir = "");

/// Weight file of the built-in Diffusion Policy backbone `dp` for a task: "<dir>/<task>.dp.asdp"
/// (docs/backbones.md, "Diffusion Policy": committed once a candidate passes its adoption rule).
std::string dp_weights_path(sim::TaskId task, const std::string& backbones_dir = "");

/// Build a backbone by name for a task. Throws actionshift::InputError (field "backbone") for an
/// unknown name, a missing or invalid weight file, or a weight file of another task; std::runtime_error
/// if an external process cannot be started.
std::unique_ptr<Policy> make_policy(std::string_view backbone, sim::TaskId task, const RegistryOptions& options = {});

/// A backbone's identity: what make_policy(backbone, task)->name() and ->sha256() give.
struct BackboneIdentity {
  std::string name;
  std::string sha256;  ///< 64-hex
};

/// The identity of a backbone without running it: an external backbone's process is not started
/// (its SHA-256 is that of its command); any other backbone is built as make_policy builds it, which
/// checks its weight file. Throws as make_policy does.
BackboneIdentity backbone_identity(std::string_view backbone, sim::TaskId task, const RegistryOptions& options = {});

/// The built-in backbone names (without the parameterised mlp:<path>, dp:<path> and external:<command>).
std::vector<std::string> builtin_backbones();

}  // namespace actionshift::policy
