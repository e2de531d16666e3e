#pragma once
/// \file
/// Proximal policy optimisation (clipped objective, GAE, Adam) of a Gaussian actor-critic on Eigen,
/// with vectorised rollouts over many environments on all cores. The actor's mean network is an MLP
/// backbone in the project's weight format (mlp.hpp; identity input normalisation, tanh hidden
/// layers, linear output); the frozen backbone acts with the mean, clipped to [-1, 1], as ManiSkill
/// evaluates its PPO baseline (deterministic policy = actor mean).
///
/// Defaults follow the ManiSkill PPO baseline (examples/baselines/ppo) where they transfer to a
/// CPU simulator: gamma 0.8, GAE lambda 0.9, learning rate 3e-4 (Adam eps 1e-5), clip 0.2, value
/// coefficient 0.5, entropy coefficient 0, gradient-norm clip 0.5, target KL 0.1, advantage
/// normalisation per minibatch, three tanh hidden layers of 256 (actor and critic), orthogonal
/// initialisation (gain sqrt 2, actor output 0.01 sqrt 2, critic output 1), a state-independent
/// log standard deviation initialised at -0.5, normalized dense reward, partial resets (an env that
/// succeeds terminates and is reset alone; a time-limit truncation bootstraps with the critic's value
/// of the final observation, and so does a success, as ManiSkill's ppo.py does). What does not transfer (4096 GPU environments x 4 steps per rollout)
/// is scaled to a CPU: fewer environments, more steps per rollout, minibatches of about the same
/// size (docs/backbones.md, "PPO").
///
/// Determinism: the same options give the same weights whatever the thread count. Each environment
/// has its own seed stream and exploration noise; environments are stepped in parallel but results
/// are stored by environment index; a minibatch gradient is the ordered sum of a fixed number of
/// chunk gradients, computed in parallel.

#include "actionshift/policy/mlp.hpp"
#include "actionshift/sim/env.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace actionshift {
class WorkerPool;  // the project's worker pool (internal: the library's own training loop passes it)
}  // namespace actionshift

namespace actionshift::policy {

/// PPO settings. Defaults: see the file comment and docs/backbones.md.
struct PpoOptions {
  sim::TaskId task{sim::TaskId::kPushCube};
  std::string profile{"maniskill"};       ///< simulator fidelity profile
  std::uint64_t seed{20260718};
  std::vector<int> hidden{256, 256, 256};  ///< hidden widths of actor and critic (tanh)
  int num_envs{64};                       ///< parallel environments
  int num_steps{16};                      ///< steps per environment per rollout
  std::int64_t total_steps{1'000'000};    ///< environment steps of the whole run
  double gamma{0.8};
  double gae_lambda{0.9};
  double learning_rate{3e-4};
  double adam_eps{1e-5};
  int num_minibatches{2};                 ///< minibatches per epoch (size = num_envs * num_steps / this)
  int update_epochs{4};
  double clip_coef{0.2};
  double vf_coef{0.5};
  double ent_coef{0.0};
  double max_grad_norm{0.5};
  double target_kl{0.1};                  ///< stop the epochs of an update once exceeded (<= 0: never)
  double init_log_std{-0.5};
  int eval_every{10};                     ///< iterations between deterministic evaluations (0: only at the end)
  int eval_episodes{32};                  ///< episodes per evaluation (training seed stream, not Gate 0's)
  unsigned threads{0};                    ///< worker threads (0: all cores)
  /// Delay-aware (augmented-state) PPO, the reference's long-lag solve: the actor and critic see the
  /// observation plus the last kHistoryLength executed canonical actions (most recent first), and
  /// every training episode runs under a lag drawn from {0, 1, 2, 4} (the identity contract plus
  /// that lag). The frozen backbone carries history = kHistoryLength (backbone `ppo-delay-aware`);
  /// evaluations split their episodes over the four lags.
  bool delay_aware{false};
  /// Bootstrap an episode that ends in success with the critic's value of its final observation, as
  /// ManiSkill's ppo.py does for every finished episode (its `final_values` cover terminations and
  /// truncations alike). false: success is terminal (value 0 after it), which with the normalized
  /// dense reward and gamma 0.8 pays more for hovering just short of the goal (about 0.6 per step,
  /// 3 in value) than for succeeding (1, then nothing): the earlier releases' setting, kept to
  /// reproduce their weights. A safety stop (this project's, ManiSkill has none) is always terminal.
  bool bootstrap_success{true};
  /// Anneal the learning rate linearly to 0 over the run (ManiSkill ppo.py's `anneal_lr`).
  bool anneal_lr{false};
  /// End the run after the first iteration that reaches this many environment steps (0: run to
  /// total_steps). The learning-rate schedule still spans total_steps, so an annealed run's checkpoint
  /// is reproduced by the same total_steps plus stop_steps = its step count.
  std::int64_t stop_steps{0};
  /// Warm start (fine-tuning): the actor mean network starts as this backbone instead of a random one
  /// (its input normalisation folded into the first layer; a reactive network's weights on the
  /// delay-aware history inputs start at 0, so the delay-aware actor starts as exactly the reactive
  /// one). Its hidden widths must equal `hidden`, its task `task`. The critic and log std start fresh
  /// (init_log_std); nullptr: a fresh actor.
  std::shared_ptr<const MlpWeights> init_actor;
  /// Iterations at the start of the run that update only the critic (the actor and log std frozen),
  /// so a warm-started actor is not pushed around by a fresh critic's advantages.
  int critic_warmup{0};
};

/// The checks train_ppo makes before it starts (the CLI makes them before it writes anything): each
/// count positive (envs at most 4096, minibatches at most envs x steps), learning rate positive and
/// finite, gamma and GAE lambda in [0, 1], evaluation counts and stop_steps non-negative, init_log_std
/// in [-5, 1], critic_warmup non-negative, hidden widths in [1, 4096]. Messages name the fields as the
/// `train ppo` options spell them ("envs: must be in [1, 4096]"). Throws actionshift::InputError.
void check_ppo_options(const PpoOptions& options);

/// One training iteration (rollout + update).
struct PpoIteration {
  int iteration{0};
  std::int64_t env_steps{0};     ///< environment steps so far
  double seconds{0.0};           ///< wall time so far
  int episodes{0};               ///< training episodes finished in this rollout
  int successes{0};              ///< of which succeeded (terminated on success)
  double mean_return{0.0};       ///< mean return of those episodes (NaN if none)
  double eval_success{-1.0};     ///< deterministic evaluation success_once (-1: not evaluated)
  double eval_return{0.0};
  double policy_loss{0.0};
  double value_loss{0.0};
  double approx_kl{0.0};
  double clip_fraction{0.0};
  double mean_std{0.0};          ///< mean exploration standard deviation
  int epochs{0};                 ///< epochs run (fewer when the target KL stopped the update)
};

/// A rollout batch, flattened: column k = one transition.
struct PpoBatch {
  Eigen::MatrixXf obs;         ///< obs_dim x N
  Eigen::MatrixXf actions;     ///< 7 x N (sampled, before clipping)
  Eigen::VectorXf log_probs;   ///< N, under the policy that collected them
  Eigen::VectorXf advantages;  ///< N (GAE)
  Eigen::VectorXf returns;     ///< N (advantages + values)
  Eigen::Index size() const { return obs.cols(); }
};

/// Statistics of one update.
struct PpoUpdateStats {
  double policy_loss{0.0}, value_loss{0.0}, approx_kl{0.0}, clip_fraction{0.0};
  int epochs{0};
};

/// Whether an episode that ended at this step is bootstrapped with the critic's value of its final
/// observation (GAE's `final_values`): a time limit yes, a success when `bootstrap_success`
/// (ManiSkill), a safety stop never.
bool bootstraps(bool success, bool truncated, sim::SafetyFlag safety, bool bootstrap_success);

/// Generalised advantage estimation over a rollout stored time-major (index t * num_envs + e).
/// `ended[k]`: the episode ended at step k (the next stored step of that env is a new episode);
/// `final_values[k]`: the critic's value of the final observation when it ended by the time limit
/// (bootstrap), 0 when it ended by success or a safety stop; `next_value[e]`: value of each env's
/// observation after the last step. Returns the advantages (returns = advantages + values).
Eigen::VectorXf gae(const Eigen::VectorXf& rewards, const Eigen::VectorXf& values, const Eigen::VectorXf& final_values,
                    const std::vector<std::uint8_t>& ended, const Eigen::VectorXf& next_value, int num_envs, double gamma,
                    double lambda);

/// Actor-critic networks and their Adam state.
class PpoLearner {
 public:
  /// Fresh networks for an input of obs_dim, initialised from options.seed.
  PpoLearner(const PpoOptions& options, int obs_dim);

  /// Actor means (7 x N, unclipped) and critic values (N) of a batch of observations (obs_dim x N).
  Eigen::MatrixXf mean(const Eigen::MatrixXf& obs) const;
  Eigen::VectorXf value(const Eigen::MatrixXf& obs) const;
  /// Log density of `actions` under N(mean, exp(log_std)^2), summed over the 7 channels.
  Eigen::VectorXf log_prob(const Eigen::MatrixXf& mean, const Eigen::MatrixXf& actions) const;
  const Eigen::VectorXf& log_std() const { return log_std_; }

  /// The clipped-objective update on a batch: update_epochs epochs of shuffled minibatches (shuffle
  /// from `shuffle_seed`), gradient computed by `threads` workers over a fixed chunking.
  PpoUpdateStats update(const PpoBatch& batch, std::uint64_t shuffle_seed, unsigned threads);
  /// The same on a pool the caller keeps (train_ppo's, shared with its environment steps): the same
  /// result whatever the pool's size.
  PpoUpdateStats update(const PpoBatch& batch, std::uint64_t shuffle_seed, WorkerPool& pool);
  /// Set the Adam learning rate of the following updates (learning-rate annealing).
  void set_learning_rate(double lr) { o_.learning_rate = lr; }
  /// Freeze the actor and log std in the following updates (only the critic learns).
  void set_actor_frozen(bool frozen) { actor_frozen_ = frozen; }

  /// The actor mean network as a backbone (identity normalisation; `training` = provenance).
  MlpWeights actor_weights(sim::TaskId task, const nlohmann::json& training) const;

  /// Dense feed-forward network: w[i] is out x in; tanh on every layer but the last.
  struct Net {
    std::vector<Eigen::MatrixXf> w;
    std::vector<Eigen::VectorXf> b;
  };

 private:
  PpoOptions o_;
  Net actor_, critic_;
  Eigen::VectorXf log_std_;
  // Adam moments, same shapes as the parameters; step count
  Net m_actor_, v_actor_, m_critic_, v_critic_;
  Eigen::VectorXf m_log_std_, v_log_std_;
  int adam_t_{0};        // critic
  int adam_t_actor_{0};  // actor and log std
  bool actor_frozen_{false};
};

/// Train with PPO. `progress` (optional) is called after every iteration; `checkpoint` (optional)
/// after every evaluation with the actor so far (its `training` field records the steps reached).
/// Throws std::invalid_argument for non-positive counts or sizes.
struct PpoResult {
  MlpWeights actor;
  std::vector<PpoIteration> iterations;
  double wall_seconds{0.0};
};
PpoResult train_ppo(const PpoOptions& options, const nlohmann::json& provenance,
                    const std::function<void(const PpoIteration&)>& progress = {},
                    const std::function<void(const MlpWeights&)>& checkpoint = {});

}  // namespace actionshift::policy
