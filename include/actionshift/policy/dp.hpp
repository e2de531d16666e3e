#pragma once
/// \file
/// Diffusion Policy backbone (docs/backbones.md, "Diffusion Policy"): the state-based conditional
/// 1-D convolutional U-Net of Chi et al. (ConditionalUnet1D) on Eigen with a hand-written backward
/// pass, and the DDPM that trains and samples it.
///
/// Network (DpArch): the input is a noisy action chunk x (action_dim x horizon), the denoising step
/// k and a global condition (the flattened stack of the last obs_horizon observations). The step is
/// embedded (sinusoidal, step_embed_dim) and passed through Linear(d, 4d) - Mish - Linear(4d, d);
/// cond = [step embedding, global condition]. Every conditional residual block is
///   out = Conv1dBlock(x); [scale, bias] = Linear(Mish(cond)); out = scale * out + bias (FiLM);
///   out = Conv1dBlock(out) + residual(x)   (residual: 1x1 Conv1d if the widths differ, else identity)
/// with Conv1dBlock = Conv1d(kernel, padding kernel/2) - GroupNorm(groups) - Mish. Down path: per
/// level two residual blocks, then (all but the last level) Conv1d(k=3, stride 2, padding 1); two
/// middle blocks; up path: per level but the first (deepest first) concatenate the skip of that
/// level, two residual blocks and ConvTranspose1d(k=4, stride 2, padding 1); final Conv1dBlock and
/// 1x1 Conv1d to action_dim. The skip of the shallowest level is not used (as in the original).
///
/// Parameters live in one flat vector (DpUnet::parameter_count()); each tensor keeps PyTorch's
/// layout: Linear (out, in), Conv1d (out, in, k), ConvTranspose1d (in, out, k), GroupNorm weight
/// then bias, row-major. The order of tensors is that of DpUnet::tensors().
///
/// Gradients: DpUnet::backward accumulates d(loss)/d(parameters) given d(loss)/d(output) for one
/// sample. The network is a class template so the gradient checks can run it in double; the
/// policy and the trainer use float.

#include "actionshift/core/rng.hpp"
#include "actionshift/policy/policy.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::policy {

/// Architecture and horizons of a Diffusion Policy network.
struct DpArch {
  int action_dim{7};
  int obs_dim{42};
  int obs_horizon{2};      ///< observations stacked into the condition
  int pred_horizon{16};    ///< length of the predicted action chunk
  int act_horizon{8};      ///< actions executed from a chunk before re-planning
  int step_embed_dim{64};  ///< diffusion-step embedding width (even, >= 4)
  std::vector<int> down_dims{64, 128, 256};
  int kernel_size{5};      ///< odd
  int groups{8};           ///< GroupNorm groups; divides every down dim
  int diffusion_steps{100};

  int cond_dim() const { return step_embed_dim + obs_horizon * obs_dim; }
  /// Throws std::invalid_argument naming the first inconsistent field.
  void validate() const;
  nlohmann::json to_json() const;
  bool operator==(const DpArch&) const = default;
};

/// One named tensor of the flat parameter vector.
struct DpTensor {
  std::string name;            ///< e.g. "down.0.0.block0.conv.weight"
  std::int64_t offset{0};
  std::vector<int> shape;      ///< PyTorch shape
  std::int64_t size() const;
};

template <class S>
using DpMat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <class S>
using DpVec = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// The conditional U-Net. Stateless: parameters are passed to every call; per-call intermediate
/// values live in a Workspace (one per thread).
template <class S>
class DpUnet {
 public:
  struct Workspace;
  explicit DpUnet(const DpArch& arch);
  ~DpUnet();
  DpUnet(const DpUnet&);
  DpUnet& operator=(const DpUnet&) = delete;

  const DpArch& arch() const { return arch_; }
  std::int64_t parameter_count() const { return count_; }
  const std::vector<DpTensor>& tensors() const { return tensors_; }

  /// PyTorch's default initialisation (weights and biases uniform in +-1/sqrt(fan_in); GroupNorm
  /// weight 1, bias 0), seeded.
  std::vector<S> init(std::uint64_t seed) const;
  /// Scratch space of forward/backward (one per thread).
  std::shared_ptr<Workspace> workspace() const;

  /// Predicted noise (action_dim x pred_horizon) for the noisy chunk x (action_dim x pred_horizon),
  /// denoising step `step` and global condition (obs_horizon * obs_dim). Keeps what backward needs
  /// in `ws`.
  DpMat<S> forward(const S* params, const DpMat<S>& x, double step, const DpVec<S>& global_cond, Workspace& ws) const;
  /// Adds d(loss)/d(params) to `grad` (parameter_count() entries) for d(loss)/d(output) = dy of the
  /// last forward on `ws`; if `dx` is given, sets it to d(loss)/d(x).
  void backward(const S* params, const DpMat<S>& dy, Workspace& ws, S* grad, DpMat<S>* dx = nullptr) const;

  /// forward() of several samples at once (one workspace each): the same bits as each sample on its
  /// own, faster, because every weight matrix is packed for the product once per batch rather than
  /// once per sample (the samples' columns are multiplied side by side, and Eigen computes each
  /// column of a product from that column alone). Used by DpLearner::step.
  std::vector<DpMat<S>> forward(const S* params, const std::vector<DpMat<S>>& x, const std::vector<double>& steps,
                                const std::vector<DpVec<S>>& global_cond, std::span<Workspace* const> ws) const;
  /// backward() of the last batched forward on `ws`: sample b adds its gradient to grads[b] (samples
  /// sharing a gradient add to it in batch order, as one-by-one calls would); returns d(loss)/d(x).
  std::vector<DpMat<S>> backward(const S* params, const std::vector<DpMat<S>>& dy, std::span<Workspace* const> ws,
                                 std::span<S* const> grads) const;

  struct Spec;  ///< layer offsets (defined in dp_net.cpp)

 private:
  DpArch arch_;
  std::int64_t count_{0};
  std::vector<DpTensor> tensors_;
  std::unique_ptr<Spec> spec_;
};

extern template class DpUnet<float>;
extern template class DpUnet<double>;

// ---- DDPM ----------------------------------------------------------------------------------------

/// DDPM noise schedule as diffusers' DDPMScheduler with beta_schedule "squaredcos_cap_v2":
/// alpha_bar(t) = cos((t + 0.008) / 1.008 * pi / 2)^2, beta_i = min(1 - alpha_bar((i+1)/T) /
/// alpha_bar(i/T), 0.999), alphas_cumprod_i = prod_{j<=i} (1 - beta_j); i = 0..T-1 (double).
struct DdpmSchedule {
  std::vector<double> betas, alphas_cumprod;
  int steps() const { return static_cast<int>(betas.size()); }
  static DdpmSchedule squaredcos_cap_v2(int steps);
};

/// One reverse step of DDPM (diffusers' DDPMScheduler.step: epsilon prediction, "fixed_small"
/// variance, clip_sample to [-1, 1] when `clip`): the sample at step t-1 from the sample x at step t
/// and the predicted noise; `noise` (same shape, standard normal) is used for t > 0.
DpMat<float> ddpm_step(const DdpmSchedule& s, int t, const DpMat<float>& x, const DpMat<float>& eps, const DpMat<float>& noise,
                       bool clip = true);

/// Samples an action chunk (action_dim x pred_horizon): DDPM over all the schedule's steps when
/// `ddim_steps` = 0, else deterministic DDIM (eta 0, "leading" spacing, clip_sample, final alpha 1)
/// over `ddim_steps` steps. Draws the initial noise (and DDPM's per-step noise) from `rng`.
DpMat<float> dp_sample(const DpUnet<float>& net, const float* params, const DdpmSchedule& schedule, const DpVec<float>& cond,
                       Rng& rng, DpUnet<float>::Workspace& ws, int ddim_steps = 0);

/// Optimiser and EMA settings (defaults: ManiSkill's state Diffusion Policy).
struct DpLearnOptions {
  double learning_rate{1e-4};  ///< AdamW peak step size
  double beta1{0.95}, beta2{0.999}, eps{1e-8};
  double weight_decay{1e-6};   ///< decoupled (AdamW)
  int warmup_steps{500};       ///< linear warm-up, then cosine decay to 0 at total_steps
  int total_steps{0};          ///< 0 = constant step size after the warm-up
  /// EMA as diffusers' EMAModel constructed from a parameter iterator with power=0.75 (use_ema_warmup
  /// stays false, so the power has no effect): decay_n = min(ema_max_decay, (1 + s) / (10 + s)) with
  /// s = n - 1 (decay 0 at the first update: the average starts at the weights).
  double ema_max_decay{0.9999};
  int shards{8};  ///< the batch is split into this many fixed shards whose gradients are summed in order
};

/// The DDPM trainer's state: weights, AdamW moments, EMA weights. step() is deterministic given the
/// seed and the batch, whatever the thread count (the batch is split into fixed shards, each summed
/// in sample order, the shards summed in shard order).
class DpLearner {
 public:
  DpLearner(const DpArch& arch, const DpLearnOptions& options, std::uint64_t seed);
  DpLearner(const DpLearner&) = delete;  // its scratch workspaces are not to be shared
  DpLearner& operator=(const DpLearner&) = delete;
  /// One AdamW step of the noise-prediction loss on a batch: actions[k] is a clean chunk
  /// (action_dim x pred_horizon, in [-1, 1]), conds[k] its condition. For each sample a step
  /// t ~ U{0..T-1} and noise ~ N(0, I) are drawn from a generator seeded by (seed, step number, k);
  /// loss = mean over the batch and entries of (eps_theta(sqrt(abar_t) x0 + sqrt(1-abar_t) eps, t) - eps)^2.
  /// Returns the loss (before the step). Throws std::invalid_argument on an empty batch or wrong shapes.
  double step(const std::vector<DpMat<float>>& actions, const std::vector<DpVec<float>>& conds, unsigned threads);

  const DpUnet<float>& net() const { return net_; }
  const DdpmSchedule& schedule() const { return schedule_; }
  const std::vector<float>& params() const { return params_; }
  const std::vector<float>& ema() const { return ema_; }
  int steps_done() const { return t_; }

  /// Everything step() changes: a checkpoint of these continues training bit for bit.
  struct State {
    int steps{0};                               ///< optimiser steps done
    std::vector<float> params, m, v, ema;       ///< weights, AdamW moments, EMA weights
  };
  State state() const { return {t_, params_, m_, v_, ema_}; }
  /// Continue from `state` (the same architecture, options and seed). Throws std::invalid_argument
  /// if a vector's size is not the network's parameter count or steps is negative.
  void restore(State state);
  /// Step size of the (1-based) optimiser step n.
  double learning_rate(int n) const;
  /// EMA decay of the (1-based) update n.
  double ema_decay(int n) const;

 private:
  DpUnet<float> net_;
  DpLearnOptions o_;
  std::uint64_t seed_;
  DdpmSchedule schedule_;
  std::vector<float> params_, m_, v_, ema_;
  int t_{0};
  std::vector<std::vector<float>> grads_;  ///< scratch: one gradient per shard
  std::vector<std::shared_ptr<DpUnet<float>::Workspace>> workspaces_;  ///< scratch: one per sample of the batch
};

// ---- weight file -------------------------------------------------------------------------------

/// A trained Diffusion Policy: architecture, observation normalisation, (EMA) weights.
///
/// Weight file format (`.asdp`, little-endian; docs/backbones.md), the container of `.asmlp`:
///   bytes 0-7   magic "ASDPW\0\0\1"
///   bytes 8-11  uint32 format version (1)
///   bytes 12-15 uint32 header length H
///   H bytes     header, UTF-8 JSON: {"format":"actionshift-dp","version":1,"task":..,"obs_dim":..,
///               "action_dim":7,"arch":{DpArch::to_json()},"scheduler":{"type":"ddpm",
///               "beta_schedule":"squaredcos_cap_v2","train_steps":..,"prediction":"epsilon",
///               "clip_sample":true},"sampler_ddim_steps":0|n,"normalization":{"obs":"mean_std",
///               "action":"none"},"weights":"ema","parameters":P,"payload_floats":N,
///               "payload_sha256":..,"training":{..}}
///   payload     N float32: obs_mean[obs_dim], obs_std[obs_dim], then the P network parameters in the
///               order of DpUnet::tensors()
/// Loading checks every field, the payload length and its SHA-256, so a truncated, corrupt or
/// wrong-shape file is a one-line actionshift::InputError naming the file and the field.
struct DpWeights {
  sim::TaskId task{sim::TaskId::kPickCube};
  DpArch arch;
  int ddim_steps{0};                    ///< sampler of the policy: 0 = DDPM over all steps, else DDIM
  Eigen::VectorXf obs_mean, obs_std;    ///< obs_norm = (obs - mean) / std, per entry
  std::vector<float> params;            ///< the (EMA) network weights
  nlohmann::json training = nlohmann::json::object();  ///< provenance (command, seed, wall time, ...)
};

/// Serialise to the `.asdp` byte format.
std::string serialize_dp(const DpWeights& w);
/// Parse the `.asdp` byte format; `source` names the file in errors. Throws actionshift::InputError.
DpWeights parse_dp(std::string_view bytes, const std::string& source);
/// Write atomically (temporary file + rename). Throws std::runtime_error on I/O failure.
void save_dp(const DpWeights& w, const std::string& path);
/// Read and parse a weight file. Throws actionshift::InputError.
DpWeights load_dp(const std::string& path);

// ---- machine-independent products ----------------------------------------------------------------

/// The L1 data-cache size every Diffusion Policy product runs under, whatever the CPU: 32 KiB.
/// Eigen blocks the depth of a matrix product by a length it derives from the L1 size it reads from
/// the CPU, and a product blocked differently rounds differently; the U-Net's deepest products (depth
/// 1,280 and 2,560 in the paper's network) are blocked. So without a fixed size the same weights and
/// episode give other actions, and other outcomes, on a machine with another L1 (48 KiB here against
/// 32 KiB where the committed files were trained and first evaluated). Only the blocking changes.
inline constexpr std::ptrdiff_t kDpEigenL1Bytes = 32 * 1024;

/// Set the L1 size Eigen assumes to kDpEigenL1Bytes (keeping its L2 and L3 sizes) unless it already
/// is. Eigen keeps one such setting per process: DpPolicy calls this on construction and before every
/// chunk it samples and does not undo it, so any other Eigen product of the process that is deep
/// enough to be blocked runs under 32 KiB from then on too. train_dp sets it for its own duration and
/// then gives the caller's setting back.
void dp_fix_eigen_l1();

// ---- policy --------------------------------------------------------------------------------------

/// The Diffusion Policy as a Policy: the last obs_horizon observations (at reset the stack is
/// filled with the reset frame) condition a sampled chunk of pred_horizon actions, of which
/// chunk[obs_horizon-1 .. obs_horizon-1+act_horizon) are executed one per step, then it re-plans
/// (and on reset). Actions are clipped to [-1, 1]. Sampling noise is seeded by the episode's first
/// observation and the chunk's index, so an episode's actions do not depend on which thread or
/// after which other episodes it runs. Name "dp:<path>" as given to the registry.
class DpPolicy final : public Policy {
 public:
  DpPolicy(std::shared_ptr<const DpWeights> weights, std::string sha256, std::string name);
  /// Load from a file (hash = SHA-256 of its bytes); name `name`, or "dp:<path>" when empty.
  static std::unique_ptr<DpPolicy> from_file(const std::string& path, std::string name = "");

  void reset() override;
  Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) override;
  std::string name() const override { return name_; }
  std::string sha256() const override { return sha256_; }
  sim::TaskId task() const override { return weights_->task; }
  std::unique_ptr<Policy> clone() const override;
  const DpWeights& weights() const { return *weights_; }
  /// Chunks sampled since construction (re-plans), for tests and benchmarks.
  std::int64_t chunks_sampled() const { return chunks_; }
  /// Condition of the last re-plan: the normalised stacked observations, oldest first.
  const DpVec<float>& last_condition() const { return cond_; }
  /// The last sampled chunk (action_dim x pred_horizon), before clipping.
  const DpMat<float>& last_chunk() const { return chunk_; }

 private:
  void plan();
  std::shared_ptr<const DpWeights> weights_;
  std::string sha256_, name_;
  std::shared_ptr<const DpUnet<float>> net_;
  std::shared_ptr<DpUnet<float>::Workspace> ws_;
  DdpmSchedule schedule_;
  std::vector<Eigen::VectorXf> frames_;  ///< normalised observations, oldest first
  DpVec<float> cond_;
  DpMat<float> chunk_;
  int next_{0};                           ///< index into the executed part of the chunk
  bool fresh_{true};                      ///< no observation seen since reset
  std::uint64_t episode_seed_{0};
  std::uint64_t chunk_index_{0};
  std::int64_t chunks_{0};
};

// ---- training from the scripted expert -----------------------------------------------------------

/// `train dp` settings. Demonstrations are episodes of the task's scripted expert (only successful
/// ones are kept); training windows follow ManiSkill's state Diffusion Policy data set: for a demo of
/// L steps, every start s in [-(obs_horizon-1), L - pred_horizon + act_horizon - 1) gives the
/// observations s .. s+obs_horizon-1 (indices < 0 repeat the first frame) and the actions
/// s .. s+pred_horizon-1 (before the start: the first action; past the end: zero motion with the last
/// gripper command). Minibatches are drawn uniformly with replacement. Deterministic from the seed
/// whatever the thread count.
struct TrainDpOptions {
  sim::TaskId task{sim::TaskId::kPickCube};
  std::string profile{"maniskill"};        ///< simulator fidelity profile of the demonstrations
  std::uint64_t seed{20260718};
  std::vector<int> down_dims{32, 64, 128};  ///< the scaled network (1.26 M parameters); paper: 64/128/256
  int demos{100};                          ///< expert episodes collected
  int iterations{1000};                    ///< optimiser steps
  int batch_size{64};
  int ddim_steps{0};                       ///< sampler recorded in the file (0 = DDPM, all steps)
  DpLearnOptions learn;                    ///< AdamW, warm-up + cosine (total = iterations), EMA
  unsigned threads{0};                     ///< demonstration and gradient threads (0 = all cores)
  int log_every{50};                       ///< progress callback period (iterations)
  /// A checkpoint file ("" = none): written atomically every `checkpoint_every` iterations, and, when it
  /// exists at the start, training continues from it, so an interrupted run ends with the same bytes as
  /// an uninterrupted one. A checkpoint written by other settings is refused (InputError naming it).
  std::string checkpoint;
  int checkpoint_every{500};               ///< iterations between checkpoints
};

/// The checks train_dp makes before it starts (the CLI makes them before it writes anything): demos,
/// iterations, batch size, log and checkpoint periods positive, the learning rate positive and finite, the
/// profile known, the U-Net widths valid for the task (DpArch::validate), ddim_steps in [0, 100].
/// Messages name the fields as the `train dp` options spell them ("down-dims: ..."). Throws
/// actionshift::InputError.
void check_train_dp_options(const TrainDpOptions& options);

/// If options.checkpoint names an existing file, reads and checks it as train_dp would before it
/// continues from it (frame, checksum, the same settings, the iteration): the CLI's check before it
/// prints anything. Returns the iteration it holds, or 0 without a checkpoint. Throws
/// actionshift::InputError naming the file.
int check_train_dp_checkpoint(const TrainDpOptions& options);

/// Progress of `train dp`.
struct TrainDpProgress {
  int iteration{0};       ///< optimiser steps done
  double loss{0.0};       ///< mean noise-prediction loss since the last report
  double seconds{0.0};    ///< wall time since the start
};

struct TrainDpResult {
  DpWeights weights;                 ///< the EMA weights; `training` left for the caller
  int demos{0}, demo_successes{0};   ///< collected, kept
  std::int64_t windows{0};           ///< training windows in the data set
  double collect_seconds{0.0}, train_seconds{0.0};
  double final_loss{0.0};            ///< mean loss over the last log period
  std::vector<TrainDpProgress> curve;  ///< every progress report, those before a resume included
  int resumed_at{0};                 ///< iteration the run continued from (0: from the start)
};

/// Collect expert demonstrations and train a Diffusion Policy. Throws std::invalid_argument for bad
/// options, std::runtime_error if no demonstration succeeds.
TrainDpResult train_dp(const TrainDpOptions& options, const std::function<void(const TrainDpProgress&)>& progress = {});

/// Parameter count of the network of `arch`.
std::int64_t dp_parameter_count(const DpArch& arch);

}  // namespace actionshift::policy
