// Leakage closed by construction: code that holds the agent-facing HiddenContractEnv must not be able
// to build the oracle's view. CTest compiles this file once per ACTIONSHIFT_NEGATIVE_CASE (each must
// fail to compile, naming OracleRecorder) and once without it (the control, which must compile, so
// the negative cases cannot pass for an unrelated reason such as a missing include).
#include "actionshift/sim/hidden_contract_env.hpp"

namespace {

[[maybe_unused]] int probe(const actionshift::sim::HiddenContractEnv& env) {
  using actionshift::sim::OracleRecorder;
#if ACTIONSHIFT_NEGATIVE_CASE == 1
  const OracleRecorder view(env, {});  // the passkey's constructor is private
  return view.contract().lag();
#elif ACTIONSHIFT_NEGATIVE_CASE == 2
  const OracleRecorder view(env);  // no constructor without the passkey
  return view.contract().lag();
#elif ACTIONSHIFT_NEGATIVE_CASE == 3
  struct Forged : OracleRecorder::Key {};  // aggregate initialisation of a derived key
  const OracleRecorder view(env, Forged{});
  return view.contract().lag();
#else
  return env.horizon();  // control: the agent-facing interface compiles
#endif
}

}  // namespace
