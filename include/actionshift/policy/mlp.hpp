#pragma once
/// \file
/// The learned MLP backbone: input normalisation, two tanh hidden layers, a linear 7-output layer
/// clipped to [-1, 1]; optionally (delay-aware) the last 4 canonical actions it emitted are appended
/// to its input, most recent first, zeros at episode start (reference section 13).
///
/// Weight file format (`.asmlp`, little-endian; docs/backbones.md):
///   bytes 0-7   magic "ASMLPW\0\1"
///   bytes 8-11  uint32 format version (1)
///   bytes 12-15 uint32 header length H
///   H bytes     header, UTF-8 JSON: {"format":"actionshift-mlp","version":1,"task":..,"obs_dim":..,
///               "history":0|4,"input_dim":..,"layers":[in,h1,h2,7],"activation":"tanh",
///               "output":"clip[-1,1]","payload_floats":N,"payload_sha256":..,"training":{..}}
///   payload     N float32: input_mean[in], input_std[in], then per layer W (out x in, row-major), b[out]
/// Loading checks every field, the payload length and its SHA-256, so a truncated, corrupt or
/// wrong-shape file is a one-line actionshift::InputError naming the file and the reason.

#include "actionshift/policy/policy.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::policy {

/// Number of past canonical actions a delay-aware network sees (reference section 13: K = 4).
inline constexpr int kHistoryLength = 4;
/// Lags a delay-aware backbone is trained under, one drawn per episode (reference section 13), by
/// `train bc --delay-aware` and `train ppo --delay-aware`.
inline constexpr int kTrainingLags[] = {0, 1, 2, 4};

/// Weights and normalisation of an MLP backbone (float32, as stored).
struct MlpWeights {
  sim::TaskId task{sim::TaskId::kPickCube};
  int history{0};                         ///< 0 or kHistoryLength past actions appended to the input
  std::vector<int> layers;                ///< sizes: input, hidden..., 7
  Eigen::VectorXf input_mean, input_std;  ///< dim layers[0]; x_norm = (x - mean) / std
  std::vector<Eigen::MatrixXf> w;         ///< w[i]: layers[i+1] x layers[i]
  std::vector<Eigen::VectorXf> b;         ///< b[i]: layers[i+1]
  nlohmann::json training = nlohmann::json::object();  ///< provenance (command, seed, wall time, ...)

  /// Input dimension = observation size + 7 * history.
  int input_dim() const { return layers.empty() ? 0 : layers.front(); }
  /// Total number of trainable parameters (weights and biases; normalisation excluded).
  std::int64_t parameter_count() const;
  /// Randomly initialised network (Xavier-uniform weights, zero biases, identity normalisation).
  static MlpWeights init(sim::TaskId task, int history, const std::vector<int>& hidden, std::uint64_t seed);
};

/// Parameter count of an MLP with these layer sizes.
std::int64_t mlp_parameter_count(const std::vector<int>& layers);

/// Serialise to the `.asmlp` byte format.
std::string serialize_mlp(const MlpWeights& w);
/// Parse the `.asmlp` byte format; `source` names the file in errors. Throws actionshift::InputError.
MlpWeights parse_mlp(std::string_view bytes, const std::string& source);
/// Write atomically (temporary file + rename). Throws std::runtime_error on I/O failure.
void save_mlp(const MlpWeights& w, const std::string& path);
/// Read and parse a weight file. Throws actionshift::InputError (file missing, truncated, corrupt,
/// wrong shape for its task).
MlpWeights load_mlp(const std::string& path);

/// Forward pass of a single normalised-input-free sample: x is the raw input (obs ++ history).
/// Output clipped to [-1, 1].
Action mlp_forward(const MlpWeights& w, const Eigen::Ref<const Eigen::VectorXf>& x);

/// The MLP as a Policy. Name "mlp" (or "mlp-delay-aware" when history > 0) unless the backbone
/// registry names it otherwise (e.g. "ppo" for a PPO-trained actor); sha256 = SHA-256 of the weight
/// file's bytes.
class MlpPolicy final : public Policy {
 public:
  /// `sha256`: hash of the bytes the weights were loaded from; `name`: "" = the default name.
  MlpPolicy(std::shared_ptr<const MlpWeights> weights, std::string sha256, std::string name = "");
  /// Load from a file (hash = SHA-256 of its bytes).
  static std::unique_ptr<MlpPolicy> from_file(const std::string& path, const std::string& name = "");

  void reset() override;
  Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) override;
  std::string name() const override;
  std::string sha256() const override { return sha256_; }
  sim::TaskId task() const override { return weights_->task; }
  std::unique_ptr<Policy> clone() const override;
  const MlpWeights& weights() const { return *weights_; }

 private:
  std::shared_ptr<const MlpWeights> weights_;
  std::string sha256_;
  std::string name_;       ///< "" = mlp / mlp-delay-aware
  Eigen::VectorXf input_;  ///< obs ++ history (most recent first)
};

}  // namespace actionshift::policy
