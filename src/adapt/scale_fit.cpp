// The scale corrector's least-squares fit (the public reference implementation's §4.7 corrector,
// fitted by least squares; see actionshift/adapt/scale_corrector.hpp). The only translation unit of
// ActionShift that includes Ceres.
#include "actionshift/adapt/scale_corrector.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace actionshift::adapt {
namespace {

// One step of the cumulative fit: O_t − k·g·C_t with k = |α| / g_w.
struct CumulativeResidual {
  double k, c, o;
  template <typename T>
  bool operator()(const T* const g, T* residual) const {
    residual[0] = T(o) - T(k) * g[0] * T(c);
    return true;
  }
};

void check_inputs(std::span<const double> abs_cmd, std::span<const double> abs_obs, double alpha, double eff_window, double lo,
                  double hi) {
  if (abs_cmd.size() != abs_obs.size() || abs_cmd.empty()) throw std::invalid_argument("scale fit: command and response lengths must match and be > 0");
  if (!std::isfinite(alpha) || alpha == 0.0) throw std::invalid_argument("scale fit: alpha must be finite and non-zero");
  if (!std::isfinite(eff_window) || !(eff_window > 0.0)) throw std::invalid_argument("scale fit: the window scale must be finite and positive");
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo > 0.0) || !(lo <= hi)) throw std::invalid_argument("scale fit: bounds must satisfy 0 < lo <= hi");
  for (std::size_t t = 0; t < abs_cmd.size(); ++t)
    if (!std::isfinite(abs_cmd[t]) || !std::isfinite(abs_obs[t])) throw std::invalid_argument("scale fit: non-finite sample");
}

}  // namespace

double fit_window_gain(std::span<const double> abs_cmd, std::span<const double> abs_obs, double alpha, double eff_window, double lo,
                       double hi) {
  check_inputs(abs_cmd, abs_obs, alpha, eff_window, lo, hi);
  const double k = std::max(std::abs(alpha), 1e-6) / eff_window;
  double g = std::clamp(eff_window, lo, hi);
  ceres::Problem::Options popt;
  ceres::Problem problem(popt);
  double c = 0.0, o = 0.0;
  for (std::size_t t = 0; t < abs_cmd.size(); ++t) {
    c += std::abs(abs_cmd[t]);
    o += std::abs(abs_obs[t]);
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CumulativeResidual, 1, 1>(new CumulativeResidual{k, c, o}), nullptr, &g);
  }
  problem.SetParameterLowerBound(&g, 0, lo);
  problem.SetParameterUpperBound(&g, 0, hi);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  options.max_num_iterations = 50;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-12;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!std::isfinite(g)) return std::clamp(eff_window, lo, hi);
  return std::clamp(g, lo, hi);
}

}  // namespace actionshift::adapt
