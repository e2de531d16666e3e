#pragma once
/// \file Adapter methods by name, with their parameters as a JSON object (the form that enters job
/// specs): oracle, no_adapt, exact_belief, fixed_probes, random_probes, entropy_probes, dualabi,
/// grammar_belief (grammar + calibration only; no pool).

#include "actionshift/adapt/adapter.hpp"
#include "actionshift/adapt/scale_corrector.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::adapt {

/// What a method may be given. Only the oracle receives `truth`, and only from the runner.
struct MethodInputs {
  const Contract* truth{nullptr};             ///< oracle only
  const std::vector<Contract>* pool{nullptr};  ///< pool-privileged methods
  const ResponseModel* model{nullptr};        ///< belief methods (from the task's calibration)
  GainFit gain_fit{nullptr};                  ///< grammar_belief's scale corrector: its least-squares fit (null: closed form)
  std::string task;                           ///< the task's name (handed to registered plug-ins)
};

/// Every method name, in ladder order (ceiling first).
const std::vector<std::string>& method_names();
bool method_needs_pool(const std::string& method);
bool method_needs_calibration(const std::string& method);

/// The method's parameters with every default filled in, validated; unknown methods or parameters
/// throw InputError(source "method", field, reason). E.g. entropy_probes → {"amplitude":0.5,
/// "budget":6,"calibrated_preview":false,"entropy_tolerance":0.0,"lag_aware_preview":false,
/// "max_active":32,"motion_tiebreak":false} (the paper's rule).
nlohmann::json resolve_method_params(const std::string& method, const nlohmann::json& params = nlohmann::json::object());

/// A named variant of a method: a preset of its parameters under a name of its own, with the reason it
/// exists. A method's bare name always means the paper's method (its defaults); a variant changes it.
struct MethodVariant {
  std::string method;      ///< the method it varies, e.g. "entropy_probes"
  std::string name;        ///< the variant's name, e.g. "calibrated"
  nlohmann::json params;   ///< the parameters it sets (a subset of the method's)
  std::string rationale;   ///< one sentence: what it changes and why (docs/adapters.md)
};

/// Every named variant: entropy_probes{calibrated} and dualabi{calibrated} (the project's calibrated,
/// lag-aware probe preview; entropy_probes's also adds the motion tie-break).
const std::vector<MethodVariant>& method_variants();

/// A method as written by a user: its name and the parameters its label sets (not yet resolved).
struct MethodLabel {
  std::string name;                                  ///< base method name, e.g. "entropy_probes"
  nlohmann::json params = nlohmann::json::object();  ///< parameters named in the label
};

/// Parses a method label: `name`, `name{variant}`, `name{key=value,...}` or `name{variant,key=value,...}`
/// (at most one variant, first). Values: true/false, integers, decimals, or text (quote text that holds
/// `,`, `{` or `}` as a JSON string). Throws InputError("method", field, reason) for a malformed label, an
/// unknown variant or a key given twice. The name itself is checked by resolve_method_params.
MethodLabel parse_method_label(std::string_view label);

/// Merges a label's parameters with explicit ones (`--params`, a YAML entry's `params`): a key given by
/// both must have the same value, else InputError("method " + name, key, reason).
nlohmann::json merge_method_params(const MethodLabel& label, const nlohmann::json& explicit_params);

/// The compact, canonical label of a method with *resolved* parameters: the bare name when every
/// parameter is the default (the paper's method); otherwise `name{...}` listing the named variant whose
/// every parameter matches (the one setting most parameters), then each remaining parameter that differs
/// from the default (or from the variant) as key=value, keys sorted. parse_method_label of the label
/// resolves to the same parameters. This label is what records and summary cells carry
/// (`method_variant`), so two variants of one method are two cells.
std::string method_variant_label(const std::string& method, const nlohmann::json& resolved_params);

/// Builds an adapter. `params` are resolved here (resolve_method_params: missing keys take their
/// defaults, so `{}` is the paper's method). Throws InputError, one line naming the method and the
/// field, for an unknown method or parameter, a value of the wrong type or range, and a missing
/// input (no pool for a pool method, no truth for the oracle).
std::unique_ptr<Adapter> make_adapter(const std::string& method, const nlohmann::json& params, const MethodInputs& in);

}  // namespace actionshift::adapt
