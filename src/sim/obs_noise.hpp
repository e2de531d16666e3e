#pragma once
// Observation (sensor) noise of the environment model (EnvConfig::obs_noise, docs/sim.md §6.1):
// internal to the sim layer, applied by Env after each observation is composed.

#include "actionshift/core/rng.hpp"
#include "actionshift/sim/task.hpp"

#include <Eigen/Core>

#include <cstdint>

namespace actionshift::sim::detail {

/// The stream tag of the noise: the noise of an episode reset with `seed` is drawn from
/// Rng(derive_seed({seed, kObsNoiseStream})), a stream no other draw uses.
inline constexpr std::uint64_t kObsNoiseStream = 0x0b5e70a15eULL;

/// Adds zero-mean Gaussian noise of standard deviation `sigma` to the observed TCP pose: each of
/// the three position coordinates gets sigma metres, and the orientation is turned by a rotation
/// vector whose three world-frame components get sigma radians (the quaternion stays unit, w >= 0).
/// Every 3-wide field named `tcp_to_*` (object minus TCP) moves by minus the same position noise, so
/// the observation stays self-consistent. Draws exactly 6 normals per call. sigma == 0: no-op, no draw.
void apply_obs_noise(const ObservationLayout& layout, double sigma, Rng& rng, Eigen::VectorXd& obs);

}  // namespace actionshift::sim::detail
