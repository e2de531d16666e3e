#pragma once
/// \file
/// Running a policy for whole episodes, unwrapped (sim::Env) or behind a hidden contract
/// (sim::HiddenContractEnv with the identity or any other contract applied to the policy's actions),
/// on all cores with one environment and one policy clone per worker thread. Episode k starts from
/// the env seed `derive_seed({seed, contract_index, k})` (docs/sim.md §9), so results do not depend
/// on the number of threads, and the unwrapped and wrapped runs see the same initial states.

#include "actionshift/core/contract.hpp"
#include "actionshift/policy/policy.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace actionshift::policy {

/// Outcome of one episode.
struct EpisodeOutcome {
  std::int64_t episode_index{0};
  std::uint64_t env_seed{0};     ///< derive_seed({seed, contract_index, episode_index})
  bool success_once{false};
  bool success_at_end{false};
  double episode_return{0.0};
  int steps{0};
  sim::SafetyFlag safety{sim::SafetyFlag::kNone};
};

/// How to run a batch of episodes.
struct RolloutOptions {
  std::uint64_t seed{20260718};           ///< experimental seed
  std::uint64_t contract_index{0};        ///< enters the env seed (0 for Gate 0)
  std::int64_t episodes{100};             ///< number of episodes (indices 0..episodes-1)
  /// nullopt: unwrapped sim::Env; otherwise the policy's actions go through a HiddenContractEnv
  /// with this contract (raw = the policy's canonical action).
  std::optional<Contract> contract;
  unsigned threads{0};                    ///< worker threads; 0 = all hardware threads
  bool stop_on_success{false};            ///< end an episode at its first success (success_at_end = true)
  /// Called after each finished episode with (finished, total); from worker threads, serialised.
  std::function<void(std::int64_t, std::int64_t)> progress;
};

/// Run one episode of `policy` (reset first) on `env` from `env_seed`.
EpisodeOutcome run_episode(sim::Env& env, Policy& policy, std::uint64_t env_seed, bool stop_on_success = false);
/// Run one episode through a hidden-contract environment.
EpisodeOutcome run_episode(sim::HiddenContractEnv& env, Policy& policy, std::uint64_t env_seed,
                           bool stop_on_success = false);

/// Run `options.episodes` episodes of clones of `policy` in parallel; results in episode order.
/// Rethrows the first exception a worker hit (e.g. an external policy that died).
std::vector<EpisodeOutcome> run_episodes(const Policy& policy, std::shared_ptr<const sim::EnvModel> model,
                                         const RolloutOptions& options);

/// Number of worker threads for a request (0 = std::thread::hardware_concurrency(), at least 1).
unsigned resolve_threads(unsigned requested);

}  // namespace actionshift::policy
