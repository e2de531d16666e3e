#include "actionshift/selftest/library.hpp"

#include "actionshift/core/reference_contracts.hpp"

#include <algorithm>

namespace actionshift::selftest {

namespace {
Contract make(std::vector<long long> perm, std::vector<long long> sign, std::vector<double> scale, long long lag = 0) {
  ContractFields f;
  f.permutation = std::move(perm);
  f.sign = std::move(sign);
  f.scale = std::move(scale);
  f.lag = lag;
  return Contract::make(f);
}
}  // namespace

std::vector<NamedContract> library() {
  // local, not namespace-scope: library() may run during another translation unit's static init
  const std::vector<long long> kId{0, 1, 2, 3, 4, 5};
  const std::vector<long long> kPlus{1, 1, 1, 1, 1, 1};
  const std::vector<double> kOne{1.0, 1.0, 1.0, 1.0, 1.0, 1.0};
  return {
      {"identity", Contract::identity()},
      {"swapped-axes", make({1, 0, 2, 3, 4, 5}, kPlus, kOne)},
      {"sign-flip", make(kId, {1, 1, 1, -1, 1, 1}, kOne)},
      {"miswired", make({1, 0, 2, 3, 4, 5}, {1, 1, 1, -1, 1, 1}, kOne)},
      {"scaled", make(kId, kPlus, {0.5, 1.0, 1.0, 1.0, 1.0, 1.0})},
      {"relabeled", make({2, 0, 1, 5, 3, 4}, {1, 1, -1, -1, 1, 1}, {2.0, 0.5, 0.75, 1.5, 1.0, 1.25})},
      {"reversed", make({5, 4, 3, 2, 1, 0}, {1, -1, -1, 1, 1, -1}, {1.5, 1.5, 0.5, 2.0, 0.75, 1.25})},
      {"lagged", make(kId, kPlus, kOne, 2)},
  };
}

std::vector<NamedContract> demos() {
  std::vector<NamedContract> d;
  for (auto& c : library())
    if (c.name != "relabeled") d.push_back(std::move(c));
  d.push_back({"unmodeled", reference::distractor_a()});
  return d;
}

std::optional<Contract> named_contract(std::string_view name) {
  for (const auto& c : library())
    if (c.name == name) return c.contract;
  if (name == "unmodeled") return reference::distractor_a();
  return std::nullopt;
}

std::string named_contract_list() {
  std::string s;
  for (const auto& c : library()) s += (s.empty() ? "" : ", ") + c.name;
  return s + ", unmodeled";
}

std::vector<Contract> with_expected(std::vector<Contract> pool, const Contract& expected) {
  if (std::find(pool.begin(), pool.end(), expected) == pool.end()) pool.push_back(expected);
  return pool;
}

std::vector<Contract> default_pool(const Contract& expected) {
  std::vector<Contract> pool;
  for (const auto& c : library()) pool.push_back(c.contract);
  return with_expected(std::move(pool), expected);
}

}  // namespace actionshift::selftest
