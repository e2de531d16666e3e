#pragma once
/// \file The unprivileged tier (docs/identifiers.md): learned identifiers that predict every field
/// of the hidden contract from the trajectory alone and then act on the prediction. No pool, no
/// grammar enumeration, no calibration, no contract: their constructors take the network only.
///
///   osi            passive, feed-forward over a fixed window of the last `window` steps
///   probe_osi      the same network, after the bounded probe phase of the belief methods (6 fixed
///                  pulses of 0.5); it estimates once, from the window that holds the probes
///   recurrent_osi  an Elman cell (tanh) over the whole episode, read out at every step
///
/// One step of evidence is 12 numbers: the raw pose action the adapter sent (6) and the TCP
/// response it caused (translation and rotation vector, 6), normalised with the training set's
/// per-feature mean and deviation. The networks end in classification heads, one softmax per
/// field and channel: permutation (6 rows x 6 raw channels), sign (6 x 2), scale (6 x the 7 grid
/// values), target (2), frame (2), lag (the 4 grid values), gripper (2): 100 logits.
///
/// Weight file format (`.asid`, little-endian), the layout of the backbones' `.asmlp`:
///   bytes 0-7   magic "ASIDW\0\0\1"
///   bytes 8-11  uint32 format version (1)
///   bytes 12-15 uint32 header length H
///   H bytes     header, UTF-8 JSON: {"format":"actionshift-identifier","version":1,"kind":..,"task":..,
///               "window":W,"recurrent":Hr,"layers":[in,h...,100],"activation":"tanh",
///               "payload_floats":N,"payload_sha256":..,"training":{..}}
///   payload     N float32: feature_mean[12], feature_std[12], then (recurrent only) Wx (Hr x 12),
///               Wh (Hr x Hr), bh[Hr], then per readout layer W (out x in, row-major), b[out]
/// Loading checks every field, the payload length and its SHA-256: a truncated, corrupt or
/// wrong-shape file is a one-line actionshift::InputError naming the file and the reason.

#include "actionshift/adapt/adapter.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/types.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::adapt {

enum class IdentifierKind { kOsi, kProbeOsi, kRecurrentOsi };
const char* identifier_kind_name(IdentifierKind k);
/// "osi", "probe_osi", "recurrent_osi"; nullopt otherwise.
std::optional<IdentifierKind> parse_identifier_kind(std::string_view name);

inline constexpr int kStepFeatures = 12;  ///< raw pose action (6) ++ TCP response (6)

/// The heads' layout in the 100 logits.
namespace heads {
inline constexpr int kPermutation = 0;   ///< 6 rows (output channel i) x 6 logits (raw channel j)
inline constexpr int kSign = 36;         ///< 6 x {-1, +1}
inline constexpr int kScale = 48;        ///< 6 x the grid {0.5, 0.6, 0.75, 1, 1.25, 1.5, 2}
inline constexpr int kTarget = 90;       ///< {delta, absolute}
inline constexpr int kFrame = 92;        ///< {base, tool}
inline constexpr int kLag = 94;          ///< the grid {0, 1, 2, 4}
inline constexpr int kGripper = 98;      ///< {not inverted, inverted}
inline constexpr int kOutputs = 100;
}  // namespace heads

/// The seven fields, in the contract's order (their accuracy is reported per field).
inline constexpr std::array<const char*, 7> kFieldNames{"permutation", "sign", "scale", "target", "frame", "lag", "gripper"};

/// Class labels of a contract, one per softmax group (permutation/sign/scale per output channel).
struct FieldLabels {
  std::array<int, kPoseDim> permutation{}, sign{}, scale{};
  int target{0}, frame{0}, lag{0}, gripper{0};
  static FieldLabels of(const Contract& c);
};

/// Per-field agreement of a prediction with the truth: for permutation, sign and scale the
/// fraction of the 6 output channels that match; for the others 0 or 1. Order of kFieldNames.
std::array<double, 7> field_agreement(const Contract& predicted, const Contract& truth);

/// The contract the logits predict: permutation by the greedy conflict-free assignment (rows in
/// order of their largest probability, each takes its most probable free raw channel), every
/// other group by its argmax.
Contract decode_logits(const Eigen::Ref<const Eigen::VectorXf>& logits);

/// Weights of an identifier (float32, as stored). Feed-forward: window > 0, recurrent == 0, the
/// readout's input is the window's normalised features, oldest first (zeros before the episode
/// starts). Recurrent: window == 0, recurrent = Hr > 0, the readout's input is the Elman state.
struct IdentifierWeights {
  IdentifierKind kind{IdentifierKind::kOsi};
  std::string task{"pick_cube"};
  int window{0};
  int recurrent{0};
  Eigen::VectorXf feature_mean, feature_std;  ///< 12 each
  Eigen::MatrixXf wx, wh;                     ///< recurrent: Hr x 12, Hr x Hr
  Eigen::VectorXf bh;                         ///< recurrent: Hr
  std::vector<int> layers;                    ///< readout sizes: input, hidden..., 100
  std::vector<Eigen::MatrixXf> w;             ///< w[i]: layers[i+1] x layers[i]
  std::vector<Eigen::VectorXf> b;
  nlohmann::json training = nlohmann::json::object();  ///< provenance and held-out verdicts

  /// Trainable parameters (normalisation excluded).
  std::int64_t parameter_count() const;
  /// Randomly initialised (Xavier-uniform weights, zero biases, identity normalisation).
  static IdentifierWeights init(IdentifierKind kind, std::string task, int window, int recurrent,
                                const std::vector<int>& hidden, std::uint64_t seed);
};

std::string serialize_identifier(const IdentifierWeights& w);
/// Throws actionshift::InputError(source, field, reason).
IdentifierWeights parse_identifier(std::string_view bytes, const std::string& source);
/// Atomic write (temporary file + rename). Throws std::runtime_error on I/O failure.
void save_identifier(const IdentifierWeights& w, const std::string& path);
IdentifierWeights load_identifier(const std::string& path);

/// Where committed identifier weights live: $ACTIONSHIFT_IDENTIFIERS_DIR if set, else the source
/// tree's configs/identifiers if it exists, else the installed <datadir>/actionshift/identifiers.
std::string default_identifiers_dir();
/// `<dir>/<weights>.<kind>.asid` for a name; `weights` itself if it contains '/' or ends in .asid.
std::string identifier_weights_path(const std::string& weights, IdentifierKind kind, const std::string& dir = "");
/// Loads once per path and process (adapters are built per episode). A file in a directory with a
/// SHA256SUMS listing it must match its line. Throws InputError (missing, corrupt, wrong kind).
std::shared_ptr<const IdentifierWeights> load_identifier_cached(const std::string& path, IdentifierKind kind);

/// One normalised step of evidence.
Eigen::VectorXf identifier_features(const IdentifierWeights& w, const Pose6& raw, const Pose6& response);

/// Per-episode inference: feed() one step of evidence at a time; logits() reads the heads after the
/// steps fed so far (feed-forward: the last `window` steps; recurrent: the Elman state).
class IdentifierState {
 public:
  explicit IdentifierState(std::shared_ptr<const IdentifierWeights> w);
  void reset();
  void feed(const Pose6& raw, const Pose6& response);
  /// Feeds an already normalised step (training and evaluation share this path).
  void feed_normalised(const Eigen::Ref<const Eigen::VectorXf>& x);
  int steps() const noexcept { return steps_; }
  Eigen::VectorXf logits() const;
  const IdentifierWeights& weights() const { return *w_; }

 private:
  std::shared_ptr<const IdentifierWeights> w_;
  int steps_{0};
  Eigen::VectorXf window_;  ///< feed-forward: W x 12, oldest first
  Eigen::VectorXf h_;       ///< recurrent state
};

/// How an identifier adapter acts (defaults: the public reference implementation's operating points).
struct IdentifierOptions {
  int warmup{8};           ///< steps of pass-through evidence before the first estimate (after any probes)
  int probe_budget{0};     ///< probe_osi: 6 fixed pulses first
  double probe_amplitude{0.5};
  bool freeze{false};      ///< estimate once (at probe_budget + warmup) and keep it; else re-estimate every step
};

/// Acts on the predicted contract: before the first estimate it sends the intent unchanged
/// (pass-through) or the probes; afterwards it encodes the intent through the predicted contract
/// with the tracked target of a decoder replica of that contract fed every raw action of the
/// episode (replayed when the estimate changes), as the oracle does with the true contract.
class IdentifierAdapter final : public Adapter {
 public:
  IdentifierAdapter(std::shared_ptr<const IdentifierWeights> weights, IdentifierOptions options);
  std::string name() const override { return identifier_kind_name(state_.weights().kind); }
  void begin_episode(std::uint64_t episode_seed) override;
  Action encode(const Action& canonical, const Mat3& R) override;
  void observe(const Action& raw, const Pose6& response, const Mat3& R) override;
  StepInfo last_step() const override { return last_; }
  /// The current estimate (nullopt before the first one).
  const std::optional<Contract>& estimate() const noexcept { return estimate_; }

 private:
  void re_estimate();
  IdentifierState state_;
  IdentifierOptions options_;
  int step_{0};
  std::optional<Contract> estimate_;
  std::vector<std::pair<Action, Mat3>> sent_;  ///< every raw action of the episode and its R
  std::optional<Decoder> replica_;  ///< decoder replica of the estimate
  StepInfo last_;
};

}  // namespace actionshift::adapt
