#pragma once
/// \file The reference's frozen 6-DoF contracts (docs/reference.md, *Contracts*) and its declared nine-contract
/// pool (docs/reference.md, *Contracts*), so results can be set beside the paper's tables.

#include "actionshift/core/contract.hpp"

#include <vector>

namespace actionshift::reference {

/// seen[0], the reference's `oracle_contract()`: perm (1,0,2,4,5,3), sign (−1,1,−1,1,−1,1),
/// scale (0.5,2.0,1.5,0.75,1.25,0.6), delta, base, lag 0, gripper inverted. Hash d1bb0bda…41a6.
inline Contract oracle_contract() {
  ContractFields f;
  f.permutation = {1, 0, 2, 4, 5, 3};
  f.sign = {-1, 1, -1, 1, -1, 1};
  f.scale = {0.5, 2.0, 1.5, 0.75, 1.25, 0.6};
  f.gripper_inverted = true;
  return Contract::make(f);
}

inline Contract with(const Contract& c, const char* target, const char* frame, int lag) {
  auto f = c.fields();
  f.target = target;
  f.frame = frame;
  f.lag = lag;
  return Contract::make(f);
}

/// The two representative contracts of a reference split: "seen", "unseen_composition" or
/// "long_lag" (contract_index 0 then 1). Throws std::invalid_argument for another name.
inline std::vector<Contract> representative_contracts(const std::string& split) {
  const Contract oc = oracle_contract();
  if (split == "seen") {
    ContractFields f;
    f.permutation = {5, 1, 2, 3, 4, 0};
    f.sign = {1, -1, 1, -1, 1, 1};
    f.scale = {1.5, 0.75, 1.0, 1.25, 0.5, 2.0};
    return {oc, Contract::make(f)};
  }
  if (split == "unseen_composition") {
    ContractFields f;
    f.permutation = {5, 4, 3, 2, 1, 0};
    f.sign = {1, -1, -1, 1, 1, -1};
    f.scale = {1.5, 1.5, 0.5, 2.0, 0.75, 1.25};
    f.target = "absolute";
    f.gripper_inverted = true;
    return {with(oc, "absolute", "tool", 0), Contract::make(f)};
  }
  if (split == "long_lag") return {with(oc, "delta", "base", 2), with(oc, "delta", "base", 4)};
  throw std::invalid_argument("unknown reference split: " + split);
}

/// Distractor A (also the self-test's out-of-pool "unmodeled" wiring). Hash 44a1aa96…28d7.
inline Contract distractor_a() {
  ContractFields f;
  f.permutation = {3, 1, 4, 0, 5, 2};
  f.sign = {-1, -1, 1, 1, -1, 1};
  f.scale = {0.6, 1.25, 0.75, 1.5, 2.0, 0.5};
  return Contract::make(f);
}

/// Distractor B. Hash b904a76d…f3e7.
inline Contract distractor_b() {
  ContractFields f;
  f.permutation = {4, 2, 0, 1, 5, 3};
  f.sign = {1, -1, 1, 1, -1, -1};
  f.scale = {1.25, 0.6, 2.0, 0.5, 1.5, 0.75};
  f.gripper_inverted = true;
  return Contract::make(f);
}

/// The declared nine-contract pool, in the reference's order (index 0 = identity, the MAP under
/// a uniform prior). pool_sha256 = b177b082…eea3.
inline std::vector<Contract> pool9() {
  std::vector<Contract> p{Contract::identity()};
  for (const char* s : {"seen", "unseen_composition", "long_lag"})
    for (const auto& c : representative_contracts(s)) p.push_back(c);
  p.push_back(distractor_a());
  p.push_back(distractor_b());
  return p;
}

}  // namespace actionshift::reference
