#pragma once
/// \file The grammar-knowledge rung (the public reference implementation's factorized full-grammar
/// belief, its §4.4 and §4.6): an adapter that knows the contract grammar's field grids and the
/// task's response calibration, and nothing else: no contract, no pool.
///
/// Under R = I the decode is separable per output channel, so the belief is factorized: for each
/// (target, lag) mode m, output channel i, raw channel j, sign s and scale k it keeps the summed
/// Gaussian log-likelihood S[m,i,j,s,k] of "output i reads raw j with gain sign_s·scale_k". The MAP
/// contract takes, per mode, the best (s,k) of every cell and the best assignment of raw channels
/// to output channels (a permutation), then the mode with the largest total. Frame is collapsed to
/// base (a tool contract cannot be represented under live rotation). The gripper inversion is an
/// independent binary factor scored on the finger channel when the calibration has one
/// (the public reference implementation's finger channel, docs/reference.md); without it the gripper is reported not inverted (unobservable).
///
/// Hold-probe excitation: during a hold window the per-step evidence is replaced by one term on
/// the window's summed response, with σ·sqrt(len): an absolute drive telescopes over the hold
/// (Σ(x_t − x_{t−1}) = the excursion) while a delta drive accumulates len × command, which tells
/// the two targets apart where single steps cannot.

#include "actionshift/adapt/adapter.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/adapt/scale_corrector.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/types.hpp"

#include <array>
#include <optional>
#include <string>

namespace actionshift::adapt {

/// The hold-probe schedule: +amplitude on channel (step / hold_steps) % channels, for
/// rounds·channels·hold_steps steps; a window closes at step % hold_steps == hold_steps − 1.
class HoldSchedule {
 public:
  /// The reference's operating point h2-r1: amplitude 0.5, hold 2, 1 round, 6 channels (12 steps).
  HoldSchedule() = default;
  /// Throws std::invalid_argument unless amplitude is finite in (0, 1], hold_steps in [2, 1000],
  /// rounds in [1, 1000] and channels in [1, 6].
  HoldSchedule(double amplitude, int hold_steps, int rounds, int channels);

  double amplitude() const noexcept { return amplitude_; }
  int hold_steps() const noexcept { return hold_steps_; }
  int rounds() const noexcept { return rounds_; }
  int channels() const noexcept { return channels_; }
  int total_steps() const noexcept { return rounds_ * channels_ * hold_steps_; }
  /// The probe at `step` (gripper 0).
  Action action(int step) const;
  bool is_window_close(int step) const noexcept { return step % hold_steps_ == hold_steps_ - 1; }
  /// "holdv1-a{amplitude}-h{hold}-r{rounds}-c{channels}", e.g. holdv1-a0.5-h2-r1-c6.
  std::string version() const;

 private:
  double amplitude_{0.5};
  int hold_steps_{2};
  int rounds_{1};
  int channels_{6};
};

/// The factorized belief over the full grammar for one environment.
class GrammarBelief {
 public:
  static constexpr int kModes = 8;   ///< (delta,0),(delta,1),(delta,2),(delta,4),(absolute,0),(absolute,1),(absolute,2),(absolute,4)
  static constexpr int kSigns = 2;   ///< −1, +1
  static constexpr int kScales = 7;  ///< the grammar's scale grid
  static constexpr int kHistory = 6;  ///< raw history depth: max lag + 2

  struct Mode {
    Target target;
    int lag;
  };
  static const std::array<Mode, kModes>& modes();

  /// The MAP of the belief: a contract on the grammar (frame base) and its mode index.
  struct Map {
    Contract contract;
    int mode{0};
    double total{0};  ///< summed evidence of the chosen cells
  };

  /// Throws std::invalid_argument for an invalid response model, invalid corrector options or a
  /// negative re-anchoring period. `scale`: run the scale corrector (the reference's §4.7) with these
  /// options; `reanchor_period` > 0: every that many updates the translation channels of the tracked
  /// target are set to the observed cumulative response (the reference's §4.8; 0 = off).
  explicit GrammarBelief(const ResponseModel& model, std::optional<ScaleCorrectorOptions> scale = std::nullopt,
                         int reanchor_period = 0);

  const ResponseModel& model() const noexcept { return model_; }

  /// Start of an episode: zero evidence, history, tracked target and hold accumulators.
  void reset();

  /// One transition: push `raw` into the history, then add the evidence of `observed` (the TCP
  /// response). `hold`: this step is a hold-probe step (its evidence only enters through the
  /// window term); `window_close`: the hold window ends with this step.
  /// `corrector_active`: the scale corrector may learn from this step (false on probe steps).
  void update(const Action& raw, const Pose6& observed, bool hold = false, bool window_close = false, bool corrector_active = true);
  /// One passive transition whose observation depends on the mode: `observed[m]` scores the cells
  /// of mode m (the log audit's exact tool-frame coordinates, where which rotation decoded the
  /// command that moved the robot depends on the lag, and an absolute target is a difference of two
  /// targets decoded under two rotations). No hold window and no scale corrector; throws
  /// std::logic_error if the belief runs the corrector or re-anchors.
  void update_per_mode(const Action& raw, const std::array<Pose6, kModes>& observed);

  /// The entropy probe (our variant; the reference runs its factorized belief passive or with fixed
  /// or hold probes only): among the 12 pulses +a·e_0..+a·e_5, −a·e_0..−a·e_5 (gripper 0), the index
  /// of the one whose predicted response is most informative about the cells. Per output channel i
  /// the belief's cell posterior p_i(m,j,s,k) ∝ exp S[m,i,j,s,k] predicts the response
  /// α_i·drive_m,j(pulse)·sign_s·scale_k (lag-aware: the pulse only drives lag-0 modes); with the
  /// same Gaussian noise σ_i under every cell, the information the response carries about the cell
  /// is its predictive entropy minus a constant, bounded by the moment-matched Gaussian's
  /// ½·log(1 + Var_i/σ_i²). The pulse maximising Σ_i of that bound is chosen (first on ties).
  /// Allocation-free; cost O(12·M·D²·S·K).
  int select_entropy_probe(double amplitude) const;
  /// The pulse of `select_entropy_probe`'s index (0..5: +a on that channel, 6..11: −a on channel − 6).
  static Action probe_candidate(int index, double amplitude);

  /// The MAP contract (cached until the next update). With zero evidence: perm identity, sign −1,
  /// scale 0.5, delta, lag 0 (the first max of every cell and the identity assignment).
  const Map& map() const;

  /// Encodes `canonical` with the MAP contract and the tracked target (R = I: the frame is
  /// collapsed to base), then, if `accumulate`, adds the canonical pose to the tracked target
  /// (the tracked target is the cumulative canonical intent).
  Action map_encode(const Action& canonical, bool accumulate = true);

  /// The finger channel: `finger_delta` observed after sending raw gripper `raw_gripper` (not
  /// lagged, as the reference). Needs a model with a finger channel (else std::logic_error).
  void observe_gripper(double raw_gripper, double finger_delta);
  /// Log-likelihood of "not inverted" (0) and "inverted" (1) from the finger channel.
  double gripper_score(int inverted) const { return gscore_[static_cast<std::size_t>(inverted)]; }

  /// Tracked target ← observed cumulative response (the hold adapter, at the end of its probe).
  void anchor_tracked_target() { target_ = observed_cumulative_; }
  /// The scale corrector, if enabled.
  const std::optional<ScaleCorrector>& corrector() const noexcept { return corrector_; }
  int reanchor_period() const noexcept { return reanchor_period_; }

  const Pose6& tracked_target() const noexcept { return target_; }
  /// S[m,i,j,s,k].
  double evidence(int m, int i, int j, int s, int k) const { return S_[index(m, i, j, s, k)]; }
  /// Steps accumulated in the open hold window.
  int hold_length() const noexcept { return hold_len_; }
  /// The drive of mode m on raw channel j for the current history (what the cells multiply).
  double drive(int m, int j) const;

 private:
  static constexpr std::size_t index(int m, int i, int j, int s, int k) {
    return static_cast<std::size_t>((((m * kPoseDim + i) * kPoseDim + j) * kSigns + s) * kScales + k);
  }
  void add_cells(const Pose6& obs, const std::array<Pose6, kModes>& base, const std::array<double, kPoseDim>& sigma);
  void add_mode_cells(int m, const Pose6& obs, const Pose6& base, const std::array<double, kPoseDim>& sigma);
  void push_history(const Action& raw);

  ResponseModel model_;
  std::array<double, kSigns * kScales> coef_{};
  std::array<double, static_cast<std::size_t>(kModes * kPoseDim * kPoseDim * kSigns * kScales)> S_{};
  std::array<Pose6, kHistory> history_{};  // history_[d] = the raw pose action d steps ago (0 = current)
  Pose6 target_{Pose6::Zero()};
  Pose6 observed_cumulative_{Pose6::Zero()};
  Pose6 hold_obs_{Pose6::Zero()};
  std::array<Pose6, kModes> hold_base_{};
  int hold_len_{0};
  std::array<double, 2> gscore_{};
  std::optional<ScaleCorrector> corrector_;
  bool have_command_{false};            // a map_encode command is waiting for its response
  Pose6 last_command_{Pose6::Zero()};   // the canonical pose of the last map_encode
  Pose6 last_eff_scale_{Pose6::Ones()}; // the scale it was encoded with
  int reanchor_period_{0};
  int steps_since_reset_{0};
  mutable bool map_valid_{false};
  mutable Map map_;
};

/// How the grammar-belief adapter excites the robot at the start of an episode.
enum class GrammarProbe { kNone, kFixed, kHold, kEntropy };

struct GrammarOptions {
  GrammarProbe probe{GrammarProbe::kNone};
  int budget{6};            ///< kFixed, kEntropy: probe steps
  double amplitude{0.5};    ///< kFixed, kEntropy: pulse amplitude
  HoldSchedule hold{};      ///< kHold: the schedule
  /// After the probe phase: act on the belief (true) or send the canonical intent unchanged
  /// (false; the causal control "flail then identity").
  bool belief_after_probe{true};
  /// Score the gripper inversion on the finger channel (the model must have one).
  bool gripper_channel{false};
  /// Run the scale corrector with these options (off when empty).
  std::optional<ScaleCorrectorOptions> scale{};
  /// Re-anchor the tracked target's translation every that many steps (0 = off).
  int reanchor_period{0};
};

/// The grammar-belief adapter (method `grammar_belief`). Privileged with the grammar and the
/// calibration only: it is constructed from a response model and options, never from a contract
/// or a pool.
class GrammarBeliefAdapter final : public Adapter {
 public:
  explicit GrammarBeliefAdapter(const ResponseModel& model, GrammarOptions options = {});
  std::string name() const override { return "grammar_belief"; }
  void begin_episode(std::uint64_t episode_seed) override;
  Action encode(const Action& canonical, const Mat3& R) override;
  void observe(const Action& raw, const Pose6& response, const Mat3& R) override;
  void observe_fingers(double finger_delta) override;
  StepInfo last_step() const override { return last_; }
  const GrammarBelief& belief() const { return belief_; }
  int probe_steps() const noexcept;

 private:
  GrammarBelief belief_;
  GrammarOptions options_;
  int steps_{0};
  int exec_step_{0};
  bool last_probe_{false};
  bool have_fingers_{false};
  double fingers_{0.0};
  StepInfo last_;
};

}  // namespace actionshift::adapt
