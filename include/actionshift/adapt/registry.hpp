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
#include <vector>

namespace actionshift::adapt {

/// What a method may be given. Only the oracle receives `truth`, and only from the runner.
struct MethodInputs {
  const Contract* truth{nullptr};             ///< oracle only
  const std::vector<Contract>* pool{nullptr};  ///< pool-privileged methods
  const ResponseModel* model{nullptr};        ///< belief methods (from the task's calibration)
  GainFit gain_fit{nullptr};                  ///< grammar_belief's scale corrector: its least-squares fit (null: closed form)
};

/// Every method name, in ladder order (ceiling first).
const std::vector<std::string>& method_names();
bool method_needs_pool(const std::string& method);
bool method_needs_calibration(const std::string& method);

/// The method's parameters with every default filled in, validated; unknown methods or parameters
/// throw InputError(source "method", field, reason). E.g. entropy_probes → {"amplitude":0.5,
/// "budget":6,"calibrated_preview":true,"lag_aware_preview":true,"max_active":32}.
nlohmann::json resolve_method_params(const std::string& method, const nlohmann::json& params = nlohmann::json::object());

/// Builds an adapter. `params` must be resolved (resolve_method_params). Throws InputError when a
/// required input is missing (no pool for a pool method, no truth for the oracle).
std::unique_ptr<Adapter> make_adapter(const std::string& method, const nlohmann::json& params, const MethodInputs& in);

}  // namespace actionshift::adapt
