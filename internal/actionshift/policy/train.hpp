#pragma once
/// \file
/// Behaviour cloning with DAgger from the scripted expert (Eigen, Adam), seeded and deterministic:
/// the same options give the same weight file bytes on the same machine whatever the number of
/// data-collection threads (episodes are collected in parallel but aggregated in episode order;
/// the optimiser runs single-threaded).
///
/// Iteration 0 rolls out the expert; iteration i > 0 rolls out a per-step mixture that executes
/// the expert's action with probability beta_i = 0.5^i and the learner's otherwise. Every visited
/// state is labelled with the expert's action and added to the data set, then the network is
/// trained for `steps_per_iteration` Adam steps on minibatches of the aggregated set.
/// Delay-aware training (history = 4): each episode runs under a lag drawn uniformly from
/// {0, 1, 2, 4} (a HiddenContractEnv whose contract is the identity plus that lag), the network
/// input is obs ++ the last 4 actions executed (most recent first), and the teacher is the
/// DelayAwareExpert told the true lag (a privileged teacher; the student has to infer the lag).

#include "actionshift/policy/mlp.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace actionshift::policy {

/// Training settings (defaults: the committed backbones, docs/backbones.md).
struct TrainBcOptions {
  sim::TaskId task{sim::TaskId::kPickCube};
  std::string profile{"maniskill"};      ///< simulator fidelity profile of the rollouts
  bool delay_aware{false};               ///< history of 4 actions, random lag {0,1,2,4}
  std::uint64_t seed{20260718};          ///< weights init, data collection, minibatches
  std::vector<int> hidden{256, 256};     ///< hidden layer widths (tanh)
  int iterations{8};                     ///< DAgger iterations (the first one is the expert's)
  int episodes_per_iteration{64};        ///< episodes collected per iteration
  int steps_per_iteration{1500};         ///< Adam steps after each collection
  int batch_size{256};
  double learning_rate{1e-3};            ///< Adam step size (decayed x0.3 in the last iteration)
  double gripper_weight{2.0};            ///< loss weight of the gripper channel
  unsigned threads{0};                   ///< data-collection threads (0 = all cores)
};

/// Statistics of one DAgger iteration.
struct TrainIteration {
  int iteration{0};
  double beta{1.0};              ///< probability of executing the expert's action
  std::int64_t samples{0};       ///< size of the aggregated data set
  int episodes{0};
  int successes{0};              ///< success_once of this iteration's (mixed) rollouts
  double loss{0.0};              ///< mean training loss of the last 100 steps
  double seconds{0.0};           ///< wall time since the start of training
};

/// Result of a training run.
struct TrainBcResult {
  MlpWeights weights;
  std::vector<TrainIteration> iterations;
  double wall_seconds{0.0};
};

/// The checks train_bc makes before it starts (the CLI makes them before it writes anything): positive
/// iterations, episodes, batch size, hidden layers and learning rate, non-negative steps. Messages name
/// the fields as the `train bc` options spell them. Throws actionshift::InputError.
void check_train_bc_options(const TrainBcOptions& options);

/// Train an MLP backbone. `progress` (optional) is called after every iteration.
/// Throws std::invalid_argument (check_train_bc_options) for non-positive counts or sizes.
TrainBcResult train_bc(const TrainBcOptions& options,
                       const std::function<void(const TrainIteration&)>& progress = {});

}  // namespace actionshift::policy
