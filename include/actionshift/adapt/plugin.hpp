#pragma once
/// \file Your own adaptation method, registered from your code (docs/methods.md): a name, a version,
/// the rung of the ladder it claims, the files that define it, and a factory that builds its Adapter
/// for each episode. Once registered, a plug-in runs like a built-in method: `resolve_method_params`,
/// `make_adapter`, plans, the runner and `actionshift compare` all accept its name, and its job id
/// names its version and the SHA-256 of its files (so editing them makes a new job).
///
/// Privilege is decided by the rung, not by the method: the runner hands a plug-in exactly what its
/// rung allows (PluginInputs) and never the hidden contract. The oracle rung is the built-in oracle's
/// alone.

#include "actionshift/adapt/adapter.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace actionshift::adapt {

/// The rungs of the ladder, most privileged first: what a method may be given.
enum class Rung {
  oracle,   ///< the true contract (the built-in `oracle` only)
  pool,     ///< the declared pool's contracts, plus everything of `grammar`
  grammar,  ///< the grammar's field grids and the task's response calibration
  none,     ///< nothing beyond what every adapter sees (intents, raw actions, responses, R, its seed)
};

/// "oracle", "pool", "grammar", "none".
std::string_view rung_name(Rung rung) noexcept;
/// Inverse of rung_name; InputError(source, field, reason) for anything else.
Rung parse_rung(std::string_view text, const std::string& source = "method", const std::string& field = "rung");
/// The rung of a method: a built-in's (oracle; the pool methods; grammar_belief; the learned
/// identifiers and no_adapt: none) or a registered plug-in's. InputError for an unknown name.
Rung method_rung(const std::string& method);

/// The contract grammar's value grids (docs/semantics.md): what the grammar rung knows.
struct GrammarGrids {
  std::vector<double> scales;             ///< per-channel scale values
  std::vector<int> lags;                  ///< lag values [control steps]
  std::vector<std::string> targets;       ///< "delta", "absolute"
  std::vector<std::string> frames;        ///< "base", "tool"
  bool permutations{true};                ///< any permutation of the six pose channels
  bool signs{true};                       ///< each pose channel ±1
  bool gripper_inversion{true};           ///< the gripper channel may be inverted
};
/// The grids of this build's grammar.
const GrammarGrids& grammar_grids();

/// What the runner hands a plug-in's factory for one episode: exactly its rung's inputs.
struct PluginInputs {
  std::string task;                              ///< task name, e.g. "pick_cube"
  Rung rung{Rung::none};                         ///< the plug-in's declared rung
  nlohmann::json params = nlohmann::json::object();  ///< the job's parameters (defaults filled in)
  const std::vector<Contract>* pool{nullptr};    ///< the declared pool (rung pool only)
  const ResponseModel* model{nullptr};           ///< the task's response calibration (rungs pool and grammar)
  const GrammarGrids* grammar{nullptr};          ///< the grammar's grids (rungs pool and grammar)
};

/// A user method. `name` is a token ([a-z0-9_.-], starting with a letter) that is not a built-in
/// method's; `version` is free text (at most 64 printable characters) that enters the job id.
struct MethodPlugin {
  std::string name;
  std::string version{"0"};
  Rung rung{Rung::none};                    ///< pool, grammar or none (oracle is refused)
  /// Files whose content defines the method (its source, weights, configuration; e.g. `{__FILE__}`):
  /// their SHA-256 enters the job id, and a job refuses to run when they changed since it was made.
  std::vector<std::string> files;
  /// Further content identity computed by the caller (e.g. a Python class's source hash), 64 hex or empty.
  std::string code_sha256;
  /// Parameters and their defaults (a JSON object): a job's parameters must be among these keys, of
  /// the same type; the resolved parameters are the defaults overridden by the job's.
  nlohmann::json params = nlohmann::json::object();
  /// Builds the method's adapter for one episode (called on runner worker threads, once per episode).
  std::function<std::unique_ptr<Adapter>(const PluginInputs&)> factory;
};

/// A registered plug-in's identity as a job records it.
struct PluginIdentity {
  std::string kind;      ///< "cpp", "python" or "external"
  std::string version;   ///< the declared version
  std::string rung;      ///< rung_name of the declared rung
  std::string sha256;    ///< content hash: sha256_hex(canonical {code_sha256, files_sha256, kind, name, rung, version})
  std::vector<std::string> files;  ///< absolute paths of the files (recorded, not part of the identity)
};

/// Removes its plug-in from the registry when destroyed (keep it for as long as the method is used;
/// a `static` one lives as long as the program).
class MethodRegistration {
 public:
  MethodRegistration() = default;
  explicit MethodRegistration(std::string name) : name_(std::move(name)) {}
  MethodRegistration(MethodRegistration&& o) noexcept : name_(std::exchange(o.name_, {})) {}
  MethodRegistration& operator=(MethodRegistration&& o) noexcept;
  MethodRegistration(const MethodRegistration&) = delete;
  MethodRegistration& operator=(const MethodRegistration&) = delete;
  ~MethodRegistration();
  const std::string& name() const noexcept { return name_; }

 private:
  std::string name_;
};

/// Registers a plug-in (thread-safe). `kind` is recorded in the job ("cpp" from C++; the Python
/// module passes "python"). Throws InputError("method " + name, field, reason) for an invalid name
/// (or a built-in's, or one already registered), the oracle rung, no factory, invalid parameters or
/// an unreadable file.
[[nodiscard]] MethodRegistration register_method(MethodPlugin plugin, const std::string& kind = "cpp");

/// The plug-in registered under `name`, or null.
std::shared_ptr<const MethodPlugin> find_method_plugin(std::string_view name);
/// Names of the registered plug-ins, sorted.
std::vector<std::string> method_plugin_names();
/// The identity of the plug-in registered under `name`, with its files hashed now (nullopt: no such plug-in).
std::optional<PluginIdentity> method_plugin_identity(std::string_view name);

}  // namespace actionshift::adapt
