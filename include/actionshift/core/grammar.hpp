#pragma once
/// \file The contract grammar's value grids (docs/semantics.md) and a seeded contract sampler.

#include "actionshift/core/contract.hpp"
#include "actionshift/core/rng.hpp"

#include <array>
#include <string>
#include <vector>

namespace actionshift::grammar {

inline constexpr std::array<double, 7> kScaleGrid{0.5, 0.6, 0.75, 1.0, 1.25, 1.5, 2.0};
inline constexpr std::array<int, 4> kLagGrid{0, 1, 2, 4};

/// Every way `c` leaves the grammar grids, one sentence each (empty: on the grid).
/// Permutation, sign, target and frame are always on their grids once a Contract is valid.
inline std::vector<std::string> violations(const Contract& c) {
  std::vector<std::string> out;
  for (int i = 0; i < kPoseDim; ++i) {
    const double s = c.scale()[static_cast<std::size_t>(i)];
    bool on = false;
    for (double g : kScaleGrid) on = on || s == g;
    if (!on) out.push_back("scale[" + std::to_string(i) + "] = " + python_float_repr(s) +
                           " is not on the grid {0.5, 0.6, 0.75, 1.0, 1.25, 1.5, 2.0}");
  }
  bool lag_on = false;
  for (int g : kLagGrid) lag_on = lag_on || c.lag() == g;
  if (!lag_on) out.push_back("lag = " + std::to_string(c.lag()) + " is not on the grid {0, 1, 2, 4}");
  return out;
}

/// True if the contract scrambles the translation block enough that a policy acting without
/// adaptation cannot do a cube task: at least two of the three translation outputs read another
/// raw channel or are sign-flipped. Used to keep evaluation splits meaningful (docs/splits.md).
inline bool is_breaking(const Contract& c) {
  int broken = 0;
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (c.permutation()[k] != i || c.sign()[k] < 0) ++broken;
  }
  return broken >= 2;
}

/// What a sampler may draw for each field. Each contract draws every field independently and
/// uniformly from its allowed values (scale per channel).
struct SamplerSpec {
  bool random_permutation{true};            ///< uniform over all 720 permutations, else identity
  bool random_sign{true};                   ///< each channel ±1, else all +1
  std::vector<double> scales{kScaleGrid.begin(), kScaleGrid.end()};  ///< per-channel choices
  std::vector<std::string> targets{"delta"};
  std::vector<std::string> frames{"base"};
  std::vector<int> lags{0};
  std::vector<bool> gripper_inverted{false, true};
};

/// One contract from `spec`, drawn with `rng` (draw order: permutation, signs, scales, target,
/// frame, lag, gripper — fixed, so a seed reproduces the same contracts).
inline Contract sample(const SamplerSpec& spec, Rng& rng) {
  ContractFields f;
  if (spec.random_permutation) rng.shuffle(f.permutation);
  if (spec.random_sign)
    for (auto& s : f.sign) s = rng.coin() ? -1 : 1;
  for (auto& s : f.scale) s = spec.scales[rng.uniform_int(spec.scales.size())];
  f.target = spec.targets[rng.uniform_int(spec.targets.size())];
  f.frame = spec.frames[rng.uniform_int(spec.frames.size())];
  f.lag = spec.lags[rng.uniform_int(spec.lags.size())];
  f.gripper_inverted = spec.gripper_inverted[rng.uniform_int(spec.gripper_inverted.size())];
  return Contract::make(f);
}

}  // namespace actionshift::grammar
