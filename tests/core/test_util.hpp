#pragma once
#include "actionshift/core/contract.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/types.hpp"

#include <Eigen/Geometry>

#include <cstdlib>

namespace actionshift::testing {

/// Seed for property tests; override with ACTIONSHIFT_TEST_SEED.
inline std::uint64_t test_seed() {
  const char* s = std::getenv("ACTIONSHIFT_TEST_SEED");
  return s ? std::strtoull(s, nullptr, 10) : 42;
}

inline Action action(std::initializer_list<double> v) {
  Action a;
  int i = 0;
  for (double x : v) a[i++] = x;
  return a;
}

inline Mat3 random_rotation(Rng& rng) {
  Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
  q.normalize();
  return q.toRotationMatrix();
}

/// Any contract of the grammar (random target, frame, lag and gripper too).
inline Contract random_contract(Rng& rng) {
  grammar::SamplerSpec s;
  s.targets = {"delta", "absolute"};
  s.frames = {"base", "tool"};
  s.lags = {0, 1, 2, 4};
  return grammar::sample(s, rng);
}

inline Action random_action(Rng& rng, double amp = 1.0) {
  Action a;
  for (int i = 0; i < kActionDim; ++i) a[i] = rng.uniform(-amp, amp);
  return a;
}

}  // namespace actionshift::testing
