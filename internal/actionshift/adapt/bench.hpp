#pragma once
/// \file Timing an adapter configuration on synthetic episodes (what `actionshift bench adapt`
/// reports): the true contract of each episode is a pool member, its own decoder executes the raw
/// actions, the response is α ⊙ executed + Gaussian noise from the response model, the TCP
/// orientation turns slowly (tool-frame contracts depend on it) and the backbone's intents are
/// smooth sinusoids. Every encode() and observe() is timed on its own.

#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace actionshift::adapt {

struct AdapterBenchConfig {
  std::string method;                               ///< a method of registry.hpp
  nlohmann::json params = nlohmann::json::object();  ///< overrides of the method's defaults
  std::vector<Contract> pool;                       ///< the declared pool (may be empty for oracle / no_adapt)
  ResponseModel model;                              ///< the response model (a task's calibration)
  int episodes{20};                                 ///< episodes per repetition (truths cycle through the pool)
  int steps{50};                                    ///< control steps per episode
  int repetitions{5};                               ///< the figures are medians over repetitions
  std::uint64_t seed{1};
};

/// Medians over the repetitions of each repetition's mean, in microseconds.
struct AdapterBenchResult {
  std::string method;
  nlohmann::json params;          ///< resolved
  int hypotheses{0};              ///< pool size (0 without a pool)
  double first_select_us{0};      ///< the first encode() of an episode: a selection from the uniform belief
  double probe_encode_us{0};      ///< encode() on steps that sent a probe (0 if none did)
  double act_encode_us{0};        ///< encode() on the other steps
  double observe_us{0};           ///< observe(): the belief update
  double step_us{0};              ///< encode() + observe() averaged over every step
  double probes_per_episode{0};   ///< mean over every episode of every repetition
  nlohmann::json to_json() const;
};

/// Throws InputError for an unknown method or parameter, or a pool method without a pool.
AdapterBenchResult bench_adapter(const AdapterBenchConfig& config);

}  // namespace actionshift::adapt
