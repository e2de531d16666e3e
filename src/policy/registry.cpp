// backbone names -> policies
#include "actionshift/policy/registry.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/policy/delay_aware.hpp"
#include "actionshift/policy/dp.hpp"
#include "actionshift/policy/expert.hpp"
#include "actionshift/policy/mlp.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace actionshift::policy {

std::string default_backbones_dir() {
  if (const char* env = std::getenv("ACTIONSHIFT_BACKBONES_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  if (std::filesystem::is_directory(ACTIONSHIFT_DEFAULT_BACKBONES_DIR, ec)) return ACTIONSHIFT_DEFAULT_BACKBONES_DIR;
  return ACTIONSHIFT_INSTALLED_BACKBONES_DIR;
}

std::string mlp_weights_path(std::string_view backbone, sim::TaskId task, const std::string& backbones_dir) {
  const std::string dir = backbones_dir.empty() ? default_backbones_dir() : backbones_dir;
  return dir + "/" + std::string(sim::task_name(task)) + "." + std::string(backbone) + ".asmlp";
}

std::string dp_weights_path(sim::TaskId task, const std::string& backbones_dir) {
  const std::string dir = backbones_dir.empty() ? default_backbones_dir() : backbones_dir;
  return dir + "/" + std::string(sim::task_name(task)) + ".dp.asdp";
}

std::vector<std::string> builtin_backbones() {
  return {"expert", "expert-delay-aware", "mlp", "mlp-delay-aware", "ppo", "ppo-delay-aware", "dp"};
}

namespace {
std::string external_command(std::string_view backbone) {
  std::string cmd(backbone.substr(9));
  if (cmd.empty()) throw InputError("", "backbone", "external: needs a command, e.g. external:python3 policy.py");
  return cmd;
}
}  // namespace

BackboneIdentity backbone_identity(std::string_view backbone, sim::TaskId task, const RegistryOptions& options) {
  if (backbone.starts_with("external:")) {
    const std::string cmd = external_command(backbone);
    return {"external:" + cmd, sha256_hex(cmd)};
  }
  const auto p = make_policy(backbone, task, options);
  return {p->name(), p->sha256()};
}

std::unique_ptr<Policy> make_policy(std::string_view backbone, sim::TaskId task, const RegistryOptions& options) {
  if (backbone == "expert") return make_expert(task);
  if (backbone == "expert-delay-aware") return std::make_unique<DelayAwareExpert>(task);
  if (backbone == "mlp" || backbone == "mlp-delay-aware" || backbone.starts_with("mlp:")) {
    const std::string path = backbone.starts_with("mlp:") ? std::string(backbone.substr(4))
                                                          : mlp_weights_path(backbone, task, options.backbones_dir);
    // a file given by path keeps its `mlp:<path>` name, so a job planned with it loads the same file
    // when it runs (the name is how the runner rebuilds the backbone; the SHA-256 checks the bytes)
    auto p = MlpPolicy::from_file(path, backbone.starts_with("mlp:") ? std::string(backbone) : std::string());
    if (p->task() != task)
      throw InputError(path, "task", "weights are for " + std::string(sim::task_name(p->task())) + ", not " +
                                         std::string(sim::task_name(task)));
    if (backbone == "mlp-delay-aware" && p->weights().history == 0)
      throw InputError(path, "history", "mlp-delay-aware needs a network with an action history");
    return p;
  }
  if (backbone == "ppo" || backbone == "ppo-delay-aware") {  // the PPO-trained actor (train ppo [--delay-aware])
    const std::string path = mlp_weights_path(backbone, task, options.backbones_dir);
    auto p = MlpPolicy::from_file(path, std::string(backbone));
    if (p->task() != task)
      throw InputError(path, "task", "weights are for " + std::string(sim::task_name(p->task())) + ", not " +
                                         std::string(sim::task_name(task)));
    if ((backbone == "ppo-delay-aware") != (p->weights().history > 0))
      throw InputError(path, "history", backbone == "ppo-delay-aware" ? "ppo-delay-aware needs a network with an action history"
                                                                      : "ppo needs a network without an action history");
    return p;
  }
  if (backbone == "dp" || backbone.starts_with("dp:")) {  // a Diffusion Policy (dp.hpp): the task's committed one, or a file
    const bool builtin = backbone == "dp";
    const std::string path = builtin ? dp_weights_path(task, options.backbones_dir) : std::string(backbone.substr(3));
    if (path.empty()) throw InputError("", "backbone", "dp: needs a weight file, e.g. dp:pick_cube.asdp");
    auto p = DpPolicy::from_file(path, builtin ? "dp" : "");
    if (p->task() != task)
      throw InputError(path, "task", "weights are for " + std::string(sim::task_name(p->task())) + ", not " +
                                         std::string(sim::task_name(task)));
    return p;
  }
  if (backbone.starts_with("external:")) {
    return std::make_unique<ExternalPolicy>(external_command(backbone), task, options.external);
  }
  throw InputError("", "backbone",
                   "unknown backbone '" + std::string(backbone) +
                       "' (valid: expert, expert-delay-aware, mlp, mlp-delay-aware, ppo, ppo-delay-aware, dp, mlp:<path>, dp:<path>, external:<command>)");
}

}  // namespace actionshift::policy
