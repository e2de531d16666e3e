#pragma once
/// \file Training and held-out evaluation of the learned identifiers (docs/identifiers.md), seeded
/// and deterministic: the same options give the same weight file bytes on the same machine,
/// whatever the number of data-collection threads (episodes are collected in parallel and
/// aggregated in order; the optimiser runs single-threaded).
///
/// Data: rollouts in the simulator under the `identifier_training` manifest's contracts (its
/// `train` list for training, its held-out `test` list for the verdicts), each step recording the
/// raw pose action sent and the TCP response. Excitation `expert`: the task's scripted expert,
/// passed through unchanged (what a passive identifier sees before it acts); `random`: uniform raw
/// pose actions in [-0.5, 0.5] (the random-excitation ablation). probe_osi's rollouts start with
/// the 6 fixed pulses of 0.5. Labels: the contract's fields as classes (adapt/identifier.hpp).
/// Loss: the sum of the 19 softmax cross-entropies; Adam. recurrent_osi: back-propagation through
/// the whole rollout (`steps` long, the episode's own length: no truncation inside it), supervised
/// at every step.

#include "actionshift/adapt/identifier.hpp"
#include "actionshift/core/contract.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace actionshift::eval {

struct TrainIdentifierOptions {
  adapt::IdentifierKind kind{adapt::IdentifierKind::kOsi};
  std::string task{"pick_cube"};
  std::string profile{"maniskill"};
  std::uint64_t seed{20260720};        ///< the public reference implementation's identifier seed
  std::string excitation{"expert"};    ///< expert | random
  int episodes_per_contract{4};
  int steps{45};                       ///< rollout length (the reference's 45)
  int window{14};                      ///< feed-forward window (the reference's 14)
  int recurrent{90};                   ///< Elman state width (matches the feed-forward budget within 1 %)
  int train_steps{3000};               ///< Adam steps
  int batch{128};                      ///< windows per step (recurrent: batch / 8 rollouts)
  double learning_rate{1e-3};
  int heldout_episodes{4};             ///< per held-out contract
  int max_contracts{0};                ///< use only the first N training / held-out contracts (0: all; tests)
  unsigned threads{0};                 ///< data-collection threads (0: all cores)
};

/// The verdicts of a trained identifier on the held-out contracts: field agreement per horizon.
struct IdentifierVerdicts {
  std::vector<int> horizons;                      ///< steps of evidence
  std::vector<std::array<double, 7>> accuracy;    ///< per horizon, per field (kFieldNames order)
  std::vector<double> exact;                      ///< per horizon: the whole contract right
  /// per horizon: mean numerical rank of the lagged regressor matrix [raw_t, raw_t-1] (12 columns)
  /// over the steps the network sees (the paper's dimensional argument, measured)
  std::vector<double> regressor_rank;
  int contracts{0}, episodes{0};
  nlohmann::json to_json() const;
};

struct TrainIdentifierResult {
  adapt::IdentifierWeights weights;
  IdentifierVerdicts heldout;
  double final_loss{0.0};
  double wall_seconds{0.0};
};

/// Parameter counts of the three kinds at these options (the budgets docs/identifiers.md states).
std::int64_t identifier_parameter_count(adapt::IdentifierKind kind, const TrainIdentifierOptions& o);

/// Held-out field agreement of `weights` under `o`'s data settings (excitation, steps, probes).
IdentifierVerdicts evaluate_identifier(const adapt::IdentifierWeights& weights, const TrainIdentifierOptions& o);

/// Train. `progress` (optional) gets one line of text now and then. Throws std::invalid_argument for
/// bad options, InputError for an unknown task or profile.
TrainIdentifierResult train_identifier(const TrainIdentifierOptions& o, const std::function<void(const std::string&)>& progress = {});

}  // namespace actionshift::eval
