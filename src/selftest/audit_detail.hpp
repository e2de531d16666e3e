#pragma once
// Internal to the audit (docs/audit.md): the log's transitions and the evidence model that identifies
// a contract from them. Not installed; shared by audit.cpp (fields, verdict, reports) and
// audit_evidence.cpp (the model).

#include "actionshift/core/contract.hpp"
#include "actionshift/core/types.hpp"
#include "actionshift/selftest/audit.hpp"

#include <array>
#include <cstddef>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::selftest::detail {

/// The output channels' names, for the reports.
inline constexpr const char* kChannel[kPoseDim] = {"x", "y", "z", "rx", "ry", "rz"};

/// One number through a printf format ("%.3g"), for the reports.
inline std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

/// One transition of a log: the action logged at t and the pose change it was followed by.
struct Step {
  Action raw;
  Pose6 response;                      // measured, physical units
  Pose6 cumulative;                    // Σ of the episode's responses through this step
  Mat3 R;                              // TCP orientation before the step
  Vec3 pos, next_pos;
  std::optional<double> finger_next;   // mean finger position after the step
  bool first{false};                   // first step of an episode
  int unit{0};                         // the jackknife's unit: the episode, or a part of a log of < 4 episodes
};
using Episodes = std::vector<std::vector<Step>>;

/// The units the jackknife and the cross-validation leave out one at a time: contiguous parts of an
/// episode, four or more in a log.
inline constexpr std::size_t kMinUnits = 4;
/// A unit is at most this many consecutive transitions of one episode: enough for the serial
/// correlation of a closed loop's residuals to stay inside it, short enough that a log has many units.
inline constexpr std::size_t kUnitSteps = 25;

Episodes transitions_of(const ActionLog& log);
int units_of(const Episodes& eps);
/// The drive of (target, lag) on raw channel j at step t of an episode (zeros before its start).
double drive(const std::vector<Step>& ep, std::size_t t, Target target, int lag, int j);
/// The response of step t in the coordinates a hypothesis (frame f: 0 base, 1 tool; target; lag)
/// decodes in, each channel divided by `alpha` first (see audit_evidence.cpp).
Pose6 working(const std::vector<Step>& ep, std::size_t t, const std::array<double, kPoseDim>& alpha, int f, Target target, int lag);

/// The largest lag the evidence model searches: the grammar's lags are 0, 1, 2, 4; the others are
/// searched so that a log outside the grammar is named so ("lag ≈ 3"), never given the nearest grid lag.
inline constexpr int kSearchLag = 6;

/// One hypothesis of the evidence model: how the command reached the robot.
struct Mode {
  Target target{Target::kDelta};
  int frame{0};  // 0 base, 1 tool
  int lag{0};
};

/// What the evidence model concluded about one output channel.
struct ChannelCall {
  int raw{-1};             ///< raw channel read (the best mode's), -1 if none stands out
  int sign{0};             ///< +1 / −1 (the best mode's)
  bool routed{false};      ///< the routing is committed (every mode the log cannot exclude agrees)
  bool sign_committed{false};
  double t{0};             ///< the best mode's t statistic of the read channel's coefficient
  double gain{0};          ///< |coefficient| in units of α (calibrated) or physical response per unit command
  double gain_se{0};       ///< its jackknife standard error over units
  double explained{0};     ///< share of the channel's motion variance the read channel explains (best mode)
  std::string why;         ///< why it is not committed, in words ("" if committed)
};

struct EvidenceOptions {
  std::array<double, kPoseDim> alpha{1, 1, 1, 1, 1, 1};  ///< response gain per output channel
  bool calibrated{false};
  double z{2.326};              ///< one-sided normal quantile of the confidence floor
  double min_explained{0.1};    ///< a read channel must explain at least this share of its output's motion
  double min_excitation{0.1};   ///< RMS raw command below which a raw channel resolves nothing
  double gain_tolerance{1.8};   ///< calibrated: a gain below grid-min / tolerance is no contract's
  double outlier_z{6.0};        ///< rows whose residual exceeds this many robust SDs are left out
  double min_margin{0.05};      ///< a rival hypothesis is excluded only if its prediction error is larger by this log ratio
  double max_coupling{0.5};     ///< a second raw channel may move an output at most this fraction of the read one's amplitude
};

struct Evidence {
  std::vector<Mode> modes;               ///< every searched hypothesis
  std::vector<double> score;             ///< cross-validated weighted residual per mode (lower is better)
  int best{0};
  std::vector<bool> plausible;           ///< not excluded by the paired test against the best
  bool evidence{false};                  ///< the best mode beats "the actions explain nothing"
  double null_t{0};                      ///< the paired t of the best mode against that null
  bool target_resolved{false}, frame_resolved{false}, lag_resolved{false};
  double target_t{0}, frame_t{0}, lag_t{0};  ///< the smallest paired t of the best mode against a rival value
  std::array<ChannelCall, kPoseDim> channel{};
  std::array<int, kPoseDim> map_perm{};  ///< the best mode's most likely permutation
  std::array<int, kPoseDim> map_sign{};
  std::array<double, kPoseDim> map_gain{};
  std::array<double, kPoseDim> residual_rms{};  ///< per output channel, best mode (working units)
  std::array<double, kPoseDim> residual_rho{};  ///< lag-1 autocorrelation of those residuals
  std::size_t outlier_rows{0};           ///< rows left out (corrupted actions, outlying responses)
  int units{0};
  double t_critical{0};                  ///< the threshold the paired and channel tests used
};

/// Identifies how the log's commands drive its motion: for every searched (target, frame, lag) a joint
/// least-squares fit of each output channel on all six raw channels, cross-validated over units; the
/// fields are those every mode the log cannot exclude agrees on (docs/audit.md, section 2).
Evidence identify(const Episodes& eps, const std::array<double, kPoseDim>& excitation, const EvidenceOptions& o);

/// The t, over units, of "a predicts better than b by more than `margin`": the log ratio of the pooled
/// prediction errors Σb/Σa, less the margin, over its jackknife standard error.
double paired_t(const std::vector<double>& a, const std::vector<double>& b, double margin);

/// The one-sided standard normal quantile of p (p in (0, 1)).
double normal_quantile(double p);

}  // namespace actionshift::selftest::detail
