#pragma once
/// \file The self-test's named wirings (docs/reference.md, *Self-test*): the default library pool of plausible
/// miswirings, and the synthetic demos (the library minus `relabeled`, plus the deliberately
/// out-of-pool `unmodeled`).

#include "actionshift/core/contract.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::selftest {

/// A contract with a human name.
struct NamedContract {
  std::string name;   ///< e.g. "swapped-axes"
  Contract contract;  ///< delta, base, gripper not inverted unless stated
};

/// The default library pool, in the reference's order: identity; swapped-axes (perm 1,0,2,3,4,5);
/// sign-flip (channel 3 negated); miswired (both); scaled (channel 0 ×0.5); relabeled; reversed;
/// lagged (lag 2). Index 0 is identity, the MAP under a uniform prior.
std::vector<NamedContract> library();

/// The synthetic demos in CLI order: identity, swapped-axes, sign-flip, miswired, scaled, reversed,
/// lagged, unmodeled. `unmodeled` (= the reference's distractor A) is outside the library pool.
std::vector<NamedContract> demos();

/// A library or demo contract by name (`unmodeled` included), or nullopt.
std::optional<Contract> named_contract(std::string_view name);

/// The names accepted by named_contract(), comma-separated (for error messages).
std::string named_contract_list();

/// `pool` with `expected` appended unless an equal contract is already in it (docs/reference.md, *Self-test*: the
/// hidden truth is never added).
std::vector<Contract> with_expected(std::vector<Contract> pool, const Contract& expected);

/// The library pool's contracts with `expected` appended if absent.
std::vector<Contract> default_pool(const Contract& expected);

}  // namespace actionshift::selftest
