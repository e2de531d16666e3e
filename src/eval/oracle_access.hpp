#pragma once
// The runner's factory of the oracle's evaluation-only view (sim::OracleRecorder). Private to the
// eval layer (not installed): the passkey OracleRecorder::Key can only be made here.

#include "actionshift/sim/hidden_contract_env.hpp"

namespace actionshift::eval::detail {

struct OracleAccess {
  static sim::OracleRecorder view(const sim::HiddenContractEnv& env) { return sim::OracleRecorder(env, sim::OracleRecorder::Key{}); }
};

}  // namespace actionshift::eval::detail
