#include "actionshift/adapt/scale_corrector.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace actionshift::adapt {

void ScaleCorrectorOptions::validate() const {
  if (window < 1 || window > 1000) throw std::invalid_argument("scale_window must be in [1, 1000]");
  if (!std::isfinite(min_correction) || !(min_correction > 0.0 && min_correction <= 1.0))
    throw std::invalid_argument("scale_min must be finite and in (0, 1]");
  if (!std::isfinite(max_correction) || !(max_correction >= 1.0)) throw std::invalid_argument("scale_max must be finite and at least 1");
  if (!std::isfinite(command_floor) || !(command_floor >= 0.0)) throw std::invalid_argument("scale_floor must be finite and nonnegative");
}

double fit_window_gain_closed_form(std::span<const double> abs_cmd, std::span<const double> abs_obs, double alpha, double eff_window,
                                   double lo, double hi) {
  if (abs_cmd.size() != abs_obs.size() || abs_cmd.empty()) throw std::invalid_argument("scale fit: command and response lengths must match and be > 0");
  const double k = std::max(std::abs(alpha), 1e-6) / eff_window;
  double c = 0.0, o = 0.0, co = 0.0, cc = 0.0;
  for (std::size_t t = 0; t < abs_cmd.size(); ++t) {
    c += std::abs(abs_cmd[t]);
    o += std::abs(abs_obs[t]);
    co += c * o;
    cc += c * c;
  }
  if (!(cc > 0.0)) return std::clamp(eff_window, lo, hi);
  return std::clamp(co / (k * cc), lo, hi);
}

ScaleCorrector::ScaleCorrector(const std::array<double, kPoseDim>& alpha, ScaleCorrectorOptions options) : options_(options) {
  options_.validate();
  for (std::size_t c = 0; c < alpha_.size(); ++c) {
    if (!std::isfinite(alpha[c])) throw std::invalid_argument("scale corrector: alpha must be finite");
    alpha_[c] = std::max(std::abs(alpha[c]), 1e-6);
  }
  cmd_.assign(static_cast<std::size_t>(options_.window * kPoseDim), 0.0);
  obs_.assign(cmd_.size(), 0.0);
  reset();
}

void ScaleCorrector::reset() {
  estimate_.setOnes();
  valid_.fill(false);
  eff_window_.setZero();
  last_eff_.setZero();
  last_valid_ = false;
  count_ = 0;
  fits_ = 0;
}

Pose6 ScaleCorrector::effective_scale(const Pose6& base) const {
  Pose6 e;
  for (int c = 0; c < kPoseDim; ++c) e[c] = std::max(valid_[static_cast<std::size_t>(c)] ? estimate_[c] : base[c], 1e-6);
  return e;
}

void ScaleCorrector::accumulate(const Pose6& cmd, const Pose6& obs, const Pose6& eff, bool active) {
  if (!active) return;
  bool changed = false;
  if (last_valid_)
    for (int c = 0; c < kPoseDim; ++c)
      if (std::abs(eff[c] - last_eff_[c]) > 1e-6 + 1e-4 * std::abs(last_eff_[c])) changed = true;
  last_eff_ = eff;
  last_valid_ = true;
  if (changed) {  // the scale the window encoded with changed: discard the window
    count_ = 0;
    return;
  }
  if (count_ == 0) eff_window_ = eff;
  const auto w = static_cast<std::size_t>(options_.window);
  for (int c = 0; c < kPoseDim; ++c) {
    const auto at = static_cast<std::size_t>(c) * w + static_cast<std::size_t>(count_);
    cmd_[at] = std::abs(cmd[c]);
    obs_[at] = std::abs(obs[c]);
  }
  ++count_;
  if (count_ >= options_.window) commit();
}

void ScaleCorrector::commit() {
  const auto w = static_cast<std::size_t>(options_.window);
  for (int c = 0; c < kPoseDim; ++c) {
    const std::span<const double> cmd(cmd_.data() + static_cast<std::size_t>(c) * w, w);
    const std::span<const double> obs(obs_.data() + static_cast<std::size_t>(c) * w, w);
    double sum = 0.0;
    for (double x : cmd) sum += x;
    if (!(sum > options_.command_floor)) continue;
    const GainFit fit = options_.fit ? options_.fit : &fit_window_gain_closed_form;
    estimate_[c] = fit(cmd, obs, alpha_[static_cast<std::size_t>(c)], eff_window_[c], options_.min_correction, options_.max_correction);
    valid_[static_cast<std::size_t>(c)] = true;
    ++fits_;
  }
  count_ = 0;
}

}  // namespace actionshift::adapt
