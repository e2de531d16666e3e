#pragma once
/// \file The scale corrector of the grammar-knowledge rung (the public reference implementation's
/// §4.7): an online per-channel gain estimate that replaces the grammar belief's MAP scale once a
/// window of task steps has been seen, for off-grid or weakly identifiable scales.
///
/// Privilege: the task's calibrated gains α only (what the grammar belief already has): it sees the
/// canonical pose the adapter commanded, the scale it encoded with and the observed response.
///
/// Each window of `window` active steps with an unchanged effective scale ends in a least-squares
/// fit per channel (done by Ceres, `fit_window_gain`, in the runs; the closed form otherwise): the cumulative observed magnitude
/// O_t = Σ_{u≤t} |obs_u| against the cumulative commanded magnitude C_t = Σ_{u≤t} |cmd_u|,
///   minimise Σ_t (O_t − |α|·(g / g_w)·C_t)²  over g ∈ [min_correction, max_correction],
/// where g_w is the scale the window encoded with (an encode with scale g_w executes g_true/g_w of
/// the command, so the fit recovers g_true). The reference's estimator is the ratio of the window's
/// sums, g_w·O_T/(|α|·C_T): the two agree when the response is proportional to the command at every
/// step, and the cumulative fit, like the sums, is insensitive to a lag of a few steps (only the last
/// terms differ) while using every step of the window. A channel is committed only if C_T exceeds
/// `command_floor` (else its estimate is not updated).

#include "actionshift/core/types.hpp"

#include <array>
#include <span>
#include <vector>

namespace actionshift::adapt {

/// A window fit: (|command| per step, |response| per step, α, the window's encoding scale, lower bound,
/// upper bound) → the gain estimate. `fit_window_gain` (Ceres, library ActionShift::fit) or
/// `fit_window_gain_closed_form` (this library).
using GainFit = double (*)(std::span<const double>, std::span<const double>, double, double, double, double);

struct ScaleCorrectorOptions {
  int window{16};               ///< active steps per fit (the reference's default), in [1, 1000]
  double min_correction{0.4};   ///< lower bound of the estimate, in (0, 1]
  double max_correction{2.5};   ///< upper bound, ≥ 1
  double command_floor{0.05};   ///< minimum C_T (summed |command| over the window) to commit a channel, ≥ 0
  /// The fit; null: the closed form. The runner (ActionShift::eval) passes the Ceres fit, so that
  /// ActionShift::adapt itself (and the self-test that links it) does not depend on Ceres.
  GainFit fit{nullptr};

  /// Throws std::invalid_argument unless 0 < min ≤ 1 ≤ max (finite), floor finite ≥ 0, window in [1, 1000].
  void validate() const;
};

/// The window's least-squares fit of one channel by Ceres (defined in library ActionShift::fit,
/// src/adapt/scale_fit.cpp, the only translation unit that includes Ceres):
/// minimises Σ_t (O_t − |alpha|·(g/eff_window)·C_t)² with C, O the cumulative sums of `abs_cmd` and
/// `abs_obs`, g bounded to [lo, hi], starting from g = eff_window clamped to the bounds.
/// Requires equal lengths, at least one step and finite inputs (else std::invalid_argument).
double fit_window_gain(std::span<const double> abs_cmd, std::span<const double> abs_obs, double alpha, double eff_window, double lo,
                       double hi);

/// The same fit in closed form (the unconstrained minimiser Σ C_t·O_t / (|α|/g_w · Σ C_t²), clamped):
/// what the tests compare the Ceres fit with.
double fit_window_gain_closed_form(std::span<const double> abs_cmd, std::span<const double> abs_obs, double alpha, double eff_window,
                                   double lo, double hi);

/// Online per-channel scale estimate for one environment.
class ScaleCorrector {
 public:
  /// Throws std::invalid_argument for invalid options or a non-finite α.
  explicit ScaleCorrector(const std::array<double, kPoseDim>& alpha, ScaleCorrectorOptions options = {});

  const ScaleCorrectorOptions& options() const noexcept { return options_; }

  /// Episode start: estimates 1, nothing valid, the window empty.
  void reset();

  /// The scale to encode with: the estimate where one was committed, else `base`; at least 1e-6.
  Pose6 effective_scale(const Pose6& base) const;

  /// One step: `cmd` the canonical pose commanded with effective scale `eff`, `obs` the response.
  /// Inactive steps (probe steps) are ignored. A change of the effective scale (any channel, beyond
  /// rtol 1e-4 / atol 1e-6) discards the open window; a full window is fitted and committed.
  void accumulate(const Pose6& cmd, const Pose6& obs, const Pose6& eff, bool active);

  const Pose6& estimate() const noexcept { return estimate_; }
  bool valid(int channel) const { return valid_[static_cast<std::size_t>(channel)]; }
  int window_count() const noexcept { return count_; }
  int fits() const noexcept { return fits_; }  ///< channel fits committed since the last reset

 private:
  void commit();

  std::array<double, kPoseDim> alpha_{};
  ScaleCorrectorOptions options_;
  Pose6 estimate_{Pose6::Ones()};
  std::array<bool, kPoseDim> valid_{};
  Pose6 eff_window_{Pose6::Zero()};
  Pose6 last_eff_{Pose6::Zero()};
  bool last_valid_{false};
  int count_{0};
  int fits_{0};
  std::vector<double> cmd_;  // window × 6, |cmd| of the open window's steps, channel-major
  std::vector<double> obs_;  // window × 6, |obs|
};

}  // namespace actionshift::adapt
