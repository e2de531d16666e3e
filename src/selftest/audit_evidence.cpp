// The audit's evidence model (docs/audit.md, section 2): how a log's commands drive its motion.
//
// For every searched hypothesis (target × frame × lag 0..kSearchLag) each output channel's response,
// in the coordinates the hypothesis decodes in, is fitted by least squares on all six raw channels at
// once (plus an intercept). A joint fit keeps collinear commands apart: a policy whose y and rx
// commands move together no longer lends one channel's evidence to the other, it widens both
// coefficients' intervals instead. Uncertainty comes from the log itself, never from a noise model:
// every coefficient's standard error is a jackknife over units (episodes, or parts of a short log), so
// serially correlated residuals, contacts and episodes that run at other gains widen it; hypotheses are
// compared by their cross-validated residual, unit by unit, with a paired t test. A field is committed
// only if every hypothesis the log cannot exclude agrees on it.
#include "audit_detail.hpp"

#include "actionshift/adapt/response.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>
#include <numeric>

namespace actionshift::selftest::detail {

Episodes transitions_of(const ActionLog& log) {
  Episodes out;
  for (const auto& ep : log.episodes) {
    std::vector<Step> steps;
    const std::size_t n = std::min(ep.actions.size(), ep.poses.empty() ? 0 : ep.poses.size() - 1);
    for (std::size_t t = 0; t < n; ++t) {
      const TcpPose& a = ep.poses[t];
      const TcpPose& b = ep.poses[t + 1];
      Step s;
      s.raw = ep.actions[t];
      const Eigen::Vector4d qa = a.quaternion / a.quaternion.norm();
      const Eigen::Vector4d qb = b.quaternion / b.quaternion.norm();
      s.response.head<3>() = b.position - a.position;
      const Eigen::Vector4d qa_conj(qa[0], -qa[1], -qa[2], -qa[3]);
      s.response.tail<3>() = adapt::quat_to_rotvec(adapt::quat_multiply(qb, qa_conj));
      s.R = Eigen::Quaterniond(qa[0], qa[1], qa[2], qa[3]).toRotationMatrix();
      s.pos = a.position;
      s.next_pos = b.position;
      if (b.fingers) s.finger_next = 0.5 * ((*b.fingers)[0] + (*b.fingers)[1]);
      s.first = t == 0;
      s.cumulative = (steps.empty() ? Pose6::Zero() : steps.back().cumulative) + s.response;
      steps.push_back(s);
    }
    if (!steps.empty()) out.push_back(std::move(steps));
  }
  // the units: contiguous parts of at most kUnitSteps transitions of one episode (a unit never spans
  // two episodes), and at least kMinUnits in all
  const std::size_t min_parts = out.size() >= kMinUnits ? 1 : (kMinUnits + out.size() - 1) / std::max<std::size_t>(out.size(), 1);
  int unit = 0;
  for (auto& ep : out) {
    const std::size_t parts = std::min(ep.size(), std::max(min_parts, (ep.size() + kUnitSteps - 1) / kUnitSteps));
    for (std::size_t t = 0; t < ep.size(); ++t) ep[t].unit = unit + static_cast<int>(t * parts / ep.size());
    unit += static_cast<int>(parts);
  }
  return out;
}

int units_of(const Episodes& eps) { return eps.empty() ? 0 : eps.back().back().unit + 1; }

// the drive of (target, lag) on raw channel j at step t of an episode (zeros before its start)
double drive(const std::vector<Step>& ep, std::size_t t, Target target, int lag, int j) {
  const auto at = [&](std::size_t d) { return t >= d ? ep[t - d].raw[j] : 0.0; };
  const double x = at(static_cast<std::size_t>(lag));
  return target == Target::kDelta ? x : x - at(static_cast<std::size_t>(lag) + 1);
}

// The response of step t in the coordinates a hypothesis (frame f, target, lag) decodes in, each
// channel divided by `alpha` first. Base frame (f = 0): as measured. Tool frame (f = 1), exactly as
// the controller decodes: the command that moved the robot at step t was decoded `lag` steps earlier,
// under that step's rotation R_{t−L}, so a delta is R_{t−L}ᵀ·response_t; an absolute target is the
// difference of two targets decoded under two rotations, and since the tracked target starts at zero
// with the episode, the cumulative response s_t is the target: R_{t−L}ᵀ·s_t − R_{t−L−1}ᵀ·s_{t−1}.
// (Reading both under the current rotation, as a first version did, is wrong by the turn between
// the two steps times the whole target: at a 1.2 rad excursion it named a tool-frame absolute log
// base frame with flipped signs.) Before the episode's start the rotation is the first step's.
Pose6 working(const std::vector<Step>& ep, std::size_t t, const std::array<double, kPoseDim>& alpha, int f, Target target, int lag) {
  const auto scaled = [&](const Pose6& v) {
    Pose6 y;
    for (int c = 0; c < kPoseDim; ++c) y[c] = v[c] / alpha[static_cast<std::size_t>(c)];
    return y;
  };
  const auto into = [&](std::size_t back, const Pose6& v) {  // v in the tool frame of step t − back
    const Mat3& Rt = ep[t >= back ? t - back : 0].R;
    Pose6 y;
    y.head<3>() = Rt.transpose() * Vec3(v.head<3>());
    y.tail<3>() = Rt.transpose() * Vec3(v.tail<3>());
    return y;
  };
  const auto L = static_cast<std::size_t>(lag);
  if (f == 0) return scaled(ep[t].response);
  if (target == Target::kDelta) return into(L, scaled(ep[t].response));
  const Pose6 now = into(L, scaled(ep[t].cumulative));
  return t == 0 ? now : Pose6(now - into(L + 1, scaled(ep[t - 1].cumulative)));
}
double normal_quantile(double p) {
  // bisection on the normal CDF: exact to 1e-12, and called a few times per audit
  double lo = -40, hi = 40;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

constexpr int kX = kPoseDim + 1;  // six raw channels and an intercept
using MatX = Eigen::Matrix<double, kX, kX>;
using MatXY = Eigen::Matrix<double, kX, kPoseDim>;
using RowX = Eigen::Matrix<double, kX, 1>;

struct Stats {
  MatX xx = MatX::Zero();
  MatXY xy = MatXY::Zero();
  Pose6 yy = Pose6::Zero();
  double n{0};
  void add(const RowX& x, const Pose6& y) {
    xx.noalias() += x * x.transpose();
    xy.noalias() += x * y.transpose();
    yy += y.cwiseProduct(y);
    n += 1;
  }
};

// Student's t quantile for the normal quantile z and df degrees of freedom: the Cornish-Fisher
// expansion (Abramowitz and Stegun 26.7.5), to the ν⁻³ term; a short log's few units pay for their
// uncertain standard errors with a higher threshold.
double t_critical(double z, int df) {
  if (df < 1) return std::numeric_limits<double>::infinity();
  const double v = df, z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
  return z + (z3 + z) / (4 * v) + (5 * z5 + 16 * z3 + 3 * z) / (96 * v * v) + (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * v * v * v);
}

MatXY solve(const MatX& xx, const MatXY& xy) {
  MatX a = xx;
  const double ridge = 1e-10 * (a.trace() / kX) + 1e-300;
  a.diagonal().array() += ridge;
  return a.ldlt().solve(xy);
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

struct Fit {
  Mode mode;
  Stats all;
  std::vector<Stats> unit;
  MatXY beta = MatXY::Zero();
  std::vector<MatXY> loo;         // leave-one-unit-out coefficients
  std::vector<Pose6> cv;          // per unit: squared prediction error of the other units' fit
  std::vector<Pose6> cv_null;     // the same for "the actions explain nothing" (intercept only)
  Pose6 rss = Pose6::Zero();      // in-sample residual sum of squares per channel
  // per output channel i and raw channel j: the mean square of the regressor through which raw j
  // drives channel i, and the mean square of channel i's motion (for the share a raw channel explains)
  Eigen::Matrix<double, kPoseDim, kPoseDim> sx2 = Eigen::Matrix<double, kPoseDim, kPoseDim>::Zero();
  Pose6 vy = Pose6::Zero();
};

bool is_tool_absolute(const Mode& m) { return m.frame == 1 && m.target == Target::kAbsolute; }

const Mat3& rotation_at(const std::vector<Step>& ep, std::size_t t, std::size_t back) { return ep[t >= back ? t - back : 0].R; }

double raw_at(const std::vector<Step>& ep, std::size_t t, std::size_t back, int j) { return t >= back ? ep[t - back].raw[j] : 0.0; }

// A tool-frame absolute target, modelled from the commands rather than from the motion: the
// controller decodes the target a(t−L) under the rotation R(t−L) and moves by the difference of two
// decoded targets, R(t−L)·M·a(t−L) − R(t−L−1)·M·a(t−L−1), M the contract's map from raw channels to
// tool-frame channels (per group: translation, rotation). Linear in M's 3 × 6 entries per group, with
// one intercept per base component. (Rotating the cumulative motion into the tool frame instead, as
// the previous model did, assumes the robot reached every target: a closed loop that pushes against
// the table accumulates targets of 50 normalised units the robot never reaches, and the turn between
// two steps times that target swamped the log.)
constexpr int kZ = 3 * kPoseDim + 3;
using VecZ = Eigen::Matrix<double, kZ, 1>;
using MatZ = Eigen::Matrix<double, kZ, kZ>;

VecZ z_row(const std::vector<Step>& ep, std::size_t t, const Mode& m, int g, int c) {
  const auto L = static_cast<std::size_t>(m.lag);
  const Mat3& R1 = rotation_at(ep, t, L);
  const Mat3& R0 = rotation_at(ep, t, L + 1);
  VecZ z = VecZ::Zero();
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < kPoseDim; ++j) z[k * kPoseDim + j] = R1(c, k) * raw_at(ep, t, L, j) - R0(c, k) * raw_at(ep, t, L + 1, j);
  z[3 * kPoseDim + c] = 1.0;
  (void)g;
  return z;
}

// the prediction of the scaled base-frame response at step t from a coefficient matrix in the
// audit's layout (beta(j, 3g + k) = M_g(k, j); beta(kPoseDim, 3g + c) the intercept of component c)
using ZRows = std::array<std::array<VecZ, 3>, 2>;  // [group][component]

ZRows z_rows(const std::vector<Step>& ep, std::size_t t, const Mode& m) {
  ZRows z;
  for (int g = 0; g < 2; ++g)
    for (int c = 0; c < 3; ++c) z[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)] = z_row(ep, t, m, g, c);
  return z;
}

Pose6 predict_tool_absolute(const MatXY& beta, const ZRows& z) {
  Pose6 p;
  for (int g = 0; g < 2; ++g)
    for (int c = 0; c < 3; ++c) {
      const VecZ& zc = z[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)];
      double v = beta(kPoseDim, 3 * g + c);
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < kPoseDim; ++j) v += beta(j, 3 * g + k) * zc[k * kPoseDim + j];
      p[3 * g + c] = v;
    }
  return p;
}

Pose6 predict_tool_absolute(const MatXY& beta, const std::vector<Step>& ep, std::size_t t, const Mode& m) {
  return predict_tool_absolute(beta, z_rows(ep, t, m));
}

Pose6 scaled_response(const std::vector<Step>& ep, std::size_t t, const std::array<double, kPoseDim>& alpha) {
  Pose6 y;
  for (int c = 0; c < kPoseDim; ++c) y[c] = ep[t].response[c] / alpha[static_cast<std::size_t>(c)];
  return y;
}

struct Masks {
  std::vector<std::vector<char>> bad_raw, bad_response;  // per episode, per step
};

// Every hypothesis is fitted on the same rows: those whose every searched lag reaches back inside the
// episode. (Padding the commands before an episode's start with zeros makes each raw channel an
// indicator of "not the first L steps", which alone explains how a policy's first steps differ from
// the rest: on a log whose actions were shuffled across rows it "explained" z at t = 5.5.)
bool excluded(const Masks& mk, std::size_t e, std::size_t t, const Mode& m) {
  if (t < static_cast<std::size_t>(kSearchLag) + 1 || mk.bad_response[e][t]) return true;
  const auto L = static_cast<std::size_t>(m.lag);
  if (t >= L && mk.bad_raw[e][t - L]) return true;
  return m.target == Target::kAbsolute && t >= L + 1 && mk.bad_raw[e][t - L - 1];
}

RowX regressors(const std::vector<Step>& ep, std::size_t t, const Mode& m) {
  RowX x;
  for (int j = 0; j < kPoseDim; ++j) x[j] = drive(ep, t, m.target, m.lag, j);
  x[kPoseDim] = 1.0;
  return x;
}

Fit fit_tool_absolute(const Episodes& eps, const Mode& m, const std::array<double, kPoseDim>& alpha, const Masks& mk, int units) {
  Fit f;
  f.mode = m;
  const auto U = static_cast<std::size_t>(units);
  struct G {
    MatZ xx = MatZ::Zero();
    VecZ xy = VecZ::Zero();
  };
  std::vector<std::array<G, 2>> unit(U);
  std::array<G, 2> all;
  std::vector<Pose6> sy(U, Pose6::Zero()), yy(U, Pose6::Zero());
  std::vector<double> n(U, 0.0);
  for (std::size_t e = 0; e < eps.size(); ++e)
    for (std::size_t t = 0; t < eps[e].size(); ++t) {
      if (excluded(mk, e, t, m)) continue;
      const auto u = static_cast<std::size_t>(eps[e][t].unit);
      const Pose6 y = scaled_response(eps[e], t, alpha);
      const ZRows zr = z_rows(eps[e], t, m);
      for (int g = 0; g < 2; ++g)
        for (int c = 0; c < 3; ++c) {
          const VecZ& z = zr[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)];
          unit[u][static_cast<std::size_t>(g)].xx.noalias() += z * z.transpose();
          unit[u][static_cast<std::size_t>(g)].xy += z * y[3 * g + c];
        }
      sy[u] += y;
      yy[u] += y.cwiseProduct(y);
      n[u] += 1;
    }
  double N = 0;
  Pose6 SY = Pose6::Zero(), YY = Pose6::Zero();
  for (std::size_t u = 0; u < U; ++u) {
    for (int g = 0; g < 2; ++g) {
      all[static_cast<std::size_t>(g)].xx += unit[u][static_cast<std::size_t>(g)].xx;
      all[static_cast<std::size_t>(g)].xy += unit[u][static_cast<std::size_t>(g)].xy;
    }
    N += n[u];
    SY += sy[u];
    YY += yy[u];
  }
  const auto solve_z = [](const MatZ& xx, const VecZ& xy) {
    MatZ a = xx;
    a.diagonal().array() += 1e-10 * (a.trace() / kZ) + 1e-300;
    return VecZ(a.ldlt().solve(xy));
  };
  const auto to_beta = [](const std::array<VecZ, 2>& th) {
    MatXY b = MatXY::Zero();
    for (int g = 0; g < 2; ++g) {
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < kPoseDim; ++j) b(j, 3 * g + k) = th[static_cast<std::size_t>(g)][k * kPoseDim + j];
      for (int c = 0; c < 3; ++c) b(kPoseDim, 3 * g + c) = th[static_cast<std::size_t>(g)][3 * kPoseDim + c];
    }
    return b;
  };
  f.beta = to_beta({solve_z(all[0].xx, all[0].xy), solve_z(all[1].xx, all[1].xy)});
  for (std::size_t u = 0; u < U; ++u) {
    if (n[u] == 0 || N - n[u] < kZ) {
      f.loo.push_back(f.beta);
      continue;
    }
    std::array<VecZ, 2> th;
    for (int g = 0; g < 2; ++g)
      th[static_cast<std::size_t>(g)] = solve_z(all[static_cast<std::size_t>(g)].xx - unit[u][static_cast<std::size_t>(g)].xx,
                                                all[static_cast<std::size_t>(g)].xy - unit[u][static_cast<std::size_t>(g)].xy);
    f.loo.push_back(to_beta(th));
  }
  // residuals: in sample, and each unit's under the fit without it; the regressors' and motion's mean squares
  f.cv.assign(U, Pose6::Zero());
  f.cv_null.assign(U, Pose6::Zero());
  for (std::size_t e = 0; e < eps.size(); ++e)
    for (std::size_t t = 0; t < eps[e].size(); ++t) {
      if (excluded(mk, e, t, m)) continue;
      const auto u = static_cast<std::size_t>(eps[e][t].unit);
      const Pose6 y = scaled_response(eps[e], t, alpha);
      const ZRows zr = z_rows(eps[e], t, m);
      const Pose6 r = y - predict_tool_absolute(f.beta, zr);
      f.rss += r.cwiseProduct(r);
      const Pose6 rc = y - predict_tool_absolute(f.loo[u], zr);
      f.cv[u] += rc.cwiseProduct(rc);
      const Mat3& R1 = rotation_at(eps[e], t, static_cast<std::size_t>(m.lag));
      for (int g = 0; g < 2; ++g)
        for (int k = 0; k < 3; ++k) {
          const Vec3 yg = y.segment<3>(3 * g);
          f.vy[3 * g + k] += std::pow(R1.col(k).dot(yg), 2);
          for (int j = 0; j < kPoseDim; ++j) {
            double ss = 0;
            for (int c = 0; c < 3; ++c) ss += std::pow(zr[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)][k * kPoseDim + j], 2);
            f.sx2(3 * g + k, j) += ss;
          }
        }
    }
  if (N > 0) {
    f.vy /= N;
    f.sx2 /= N;
  }
  for (std::size_t u = 0; u < U; ++u) {
    if (n[u] == 0 || N - n[u] < 1) continue;
    for (int c = 0; c < kPoseDim; ++c) {
      const double mean = (SY[c] - sy[u][c]) / (N - n[u]);
      f.cv_null[u][c] = std::max(yy[u][c] - 2.0 * mean * sy[u][c] + n[u] * mean * mean, 0.0);
    }
  }
  f.unit.assign(U, Stats{});
  for (std::size_t u = 0; u < U; ++u) f.unit[u].n = n[u];
  f.all.n = N;
  return f;
}

Fit fit_mode(const Episodes& eps, const Mode& m, const std::array<double, kPoseDim>& alpha, const Masks& mk, int units) {
  if (is_tool_absolute(m)) return fit_tool_absolute(eps, m, alpha, mk, units);
  Fit f;
  f.mode = m;
  f.unit.assign(static_cast<std::size_t>(units), Stats{});
  for (std::size_t e = 0; e < eps.size(); ++e)
    for (std::size_t t = 0; t < eps[e].size(); ++t) {
      if (excluded(mk, e, t, m)) continue;
      const RowX x = regressors(eps[e], t, m);
      const Pose6 y = working(eps[e], t, alpha, m.frame, m.target, m.lag);
      f.unit[static_cast<std::size_t>(eps[e][t].unit)].add(x, y);
    }
  for (const auto& u : f.unit) {
    f.all.xx += u.xx;
    f.all.xy += u.xy;
    f.all.yy += u.yy;
    f.all.n += u.n;
  }
  f.beta = solve(f.all.xx, f.all.xy);
  const auto rss_of = [](const Stats& s, const MatXY& b) {
    Pose6 r;
    for (int c = 0; c < kPoseDim; ++c) {
      const auto bc = b.col(c);
      r[c] = std::max(s.yy[c] - 2.0 * bc.dot(s.xy.col(c)) + bc.dot(s.xx * bc), 0.0);
    }
    return r;
  };
  f.rss = rss_of(f.all, f.beta);
  for (const auto& u : f.unit) {
    if (u.n == 0 || f.all.n - u.n < kX) {
      f.loo.push_back(f.beta);
      f.cv.push_back(Pose6::Zero());
      f.cv_null.push_back(Pose6::Zero());
      continue;
    }
    const MatXY b = solve(f.all.xx - u.xx, f.all.xy - u.xy);
    f.loo.push_back(b);
    f.cv.push_back(rss_of(u, b));
    Pose6 nul;
    for (int c = 0; c < kPoseDim; ++c) {
      const double mean = (f.all.xy(kPoseDim, c) - u.xy(kPoseDim, c)) / (f.all.n - u.n);
      nul[c] = std::max(u.yy[c] - 2.0 * mean * u.xy(kPoseDim, c) + u.n * mean * mean, 0.0);
    }
    f.cv_null.push_back(nul);
  }
  const double n = std::max(f.all.n, 1.0);
  for (int i = 0; i < kPoseDim; ++i) {
    f.vy[i] = f.all.yy[i] / n - std::pow(f.all.xy(kPoseDim, i) / n, 2);
    for (int j = 0; j < kPoseDim; ++j) f.sx2(i, j) = f.all.xx(j, j) / n - std::pow(f.all.xx(j, kPoseDim) / n, 2);
  }
  return f;
}

// the residual of step t under a fit (scaled response in the mode's working coordinates minus the prediction)
Pose6 residual(const Fit& f, const MatXY& beta, const std::vector<Step>& ep, std::size_t t, const std::array<double, kPoseDim>& alpha) {
  const Mode& m = f.mode;
  if (is_tool_absolute(m)) return scaled_response(ep, t, alpha) - predict_tool_absolute(beta, ep, t, m);
  return working(ep, t, alpha, m.frame, m.target, m.lag) - beta.transpose() * regressors(ep, t, m);
}

struct Paired {
  double t{0};
  int n{0};
};

// paired t of "a predicts better than b by more than `margin`", over units: the log of the ratio of
// the pooled prediction errors, log(Σb / Σa), less the margin, over its jackknife standard error
// (each unit left out in turn). Pooled, so that units in which the robot holds still (a scripted
// policy's grasp) do not dilute the comparison; jackknifed, so that a unit that carries the whole
// difference (one episode's contact) leaves it undecided.
Paired paired(const std::vector<double>& a, const std::vector<double>& b, const std::vector<char>& used, double margin = 0.0) {
  double sa = 0, sb = 0;
  int k = 0;
  for (std::size_t u = 0; u < a.size(); ++u)
    if (used[u]) {
      sa += a[u];
      sb += b[u];
      ++k;
    }
  Paired p;
  p.n = k;
  if (k < 2) return p;
  const double eps = 1e-12 * std::max(sa, sb) + 1e-300;
  const double r = std::log((sb + eps) / (sa + eps));
  std::vector<double> loo;
  for (std::size_t u = 0; u < a.size(); ++u)
    if (used[u]) loo.push_back(std::log((sb - b[u] + eps) / (sa - a[u] + eps)));
  const double kk = static_cast<double>(loo.size());
  double mean = 0, ss = 0;
  for (double x : loo) mean += x / kk;
  for (double x : loo) ss += (x - mean) * (x - mean);
  const double se = std::sqrt(ss * (kk - 1) / kk);
  if (se <= 1e-12) {
    p.t = r - margin > 1e-9 ? std::numeric_limits<double>::infinity() : 0.0;
    return p;
  }
  p.t = (r - margin) / se;
  return p;
}

// jackknife standard error of a scalar computed from each unit's leave-out estimate
double jackknife_se(const std::vector<double>& v) {
  if (v.size() < 2) return std::numeric_limits<double>::infinity();
  const double k = static_cast<double>(v.size());
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / k;
  double ss = 0;
  for (double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss * (k - 1) / k);
}

std::string mode_words(const Mode& m) {
  return std::string(to_string(m.target)) + "/" + (m.frame ? "tool" : "base") + "/lag " + std::to_string(m.lag);
}


}  // namespace

double paired_t(const std::vector<double>& a, const std::vector<double>& b, double margin) {
  return paired(a, b, std::vector<char>(a.size(), 1), margin).t;
}

Evidence identify(const Episodes& eps, const std::array<double, kPoseDim>& excitation, const EvidenceOptions& o) {
  Evidence ev;
  for (Target target : {Target::kDelta, Target::kAbsolute})
    for (int frame = 0; frame < 2; ++frame)
      for (int lag = 0; lag <= kSearchLag; ++lag) ev.modes.push_back(Mode{target, frame, lag});
  const int units = units_of(eps);
  ev.units = units;
  Masks mk;
  for (const auto& ep : eps) {
    mk.bad_raw.emplace_back(ep.size(), 0);
    mk.bad_response.emplace_back(ep.size(), 0);
  }
  // corrupted action cells: far outside what the log's commands otherwise span
  for (int j = 0; j < kPoseDim; ++j) {
    std::vector<double> a;
    for (const auto& ep : eps)
      for (const auto& s : ep) a.push_back(std::abs(s.raw[j]));
    const double q = quantile(a, 0.995);
    for (std::size_t e = 0; e < eps.size(); ++e)
      for (std::size_t t = 0; t < eps[e].size(); ++t)
        if (std::abs(eps[e][t].raw[j]) > 3.0 * q + 1e-9) mk.bad_raw[e][t] = 1;
  }

  std::vector<Fit> fits;
  std::array<double, kPoseDim> w{};
  const auto fit_all = [&] {
    fits.clear();
    for (const auto& m : ev.modes) fits.push_back(fit_mode(eps, m, o.alpha, mk, units));
    // channel weights: the smallest residual variance any mode reaches, one per group (translation,
    // rotation), so that a fixed rotation of the coordinates (a tool frame that does not turn) changes
    // no score
    std::array<double, kPoseDim> s2{};
    for (int c = 0; c < kPoseDim; ++c) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& f : fits)
        if (f.all.n > 0) best = std::min(best, f.rss[c] / f.all.n);
      s2[static_cast<std::size_t>(c)] = std::isfinite(best) ? best : 1.0;
    }
    for (int g = 0; g < 2; ++g) {
      double m = 0;
      for (int c = 3 * g; c < 3 * g + 3; ++c) m += s2[static_cast<std::size_t>(c)] / 3.0;
      for (int c = 3 * g; c < 3 * g + 3; ++c) w[static_cast<std::size_t>(c)] = 1.0 / std::max(m, 1e-30);
    }
    ev.score.assign(fits.size(), 0.0);
    for (std::size_t k = 0; k < fits.size(); ++k)
      for (const auto& cv : fits[k].cv)
        for (int c = 0; c < kPoseDim; ++c) ev.score[k] += w[static_cast<std::size_t>(c)] * cv[c];
    ev.best = 0;
    for (std::size_t k = 1; k < fits.size(); ++k)
      if (ev.score[k] < ev.score[static_cast<std::size_t>(ev.best)]) ev.best = static_cast<int>(k);
  };
  fit_all();
  // outlying rows under the best mode (a corrupted action cell inside the commands' range, a contact):
  // left out of every mode, and the fits repeated once
  {
    const Fit& b = fits[static_cast<std::size_t>(ev.best)];
    std::vector<std::vector<Pose6>> res(eps.size());
    std::array<std::vector<double>, kPoseDim> absr;
    for (std::size_t e = 0; e < eps.size(); ++e)
      for (std::size_t t = 0; t < eps[e].size(); ++t) {
        if (excluded(mk, e, t, b.mode)) {
          res[e].push_back(Pose6::Zero());
          continue;
        }
        const Pose6 r = residual(b, b.beta, eps[e], t, o.alpha);
        res[e].push_back(r);
        for (int c = 0; c < kPoseDim; ++c) absr[static_cast<std::size_t>(c)].push_back(std::abs(r[c]));
      }
    // a robust residual scale per channel: the larger of the MAD's and the 90th percentile's normal
    // equivalents (a scripted policy holds still for long stretches, where residuals are near zero
    // and the MAD alone would call every moving row an outlier)
    std::array<double, kPoseDim> scale{};
    for (int c = 0; c < kPoseDim; ++c) {
      const auto& v = absr[static_cast<std::size_t>(c)];
      scale[static_cast<std::size_t>(c)] = std::max(1.4826 * quantile(v, 0.5), quantile(v, 0.9) / 1.645);
    }
    // each row's largest standardised residual; at most 1 % of the rows are left out (a heavier tail
    // than that is the log's own distribution, not a few corrupted rows)
    std::vector<std::pair<double, std::pair<std::size_t, std::size_t>>> worst;
    for (std::size_t e = 0; e < eps.size(); ++e)
      for (std::size_t t = 0; t < eps[e].size(); ++t) {
        double z = 0;
        for (int c = 0; c < kPoseDim; ++c) {
          const double sc = scale[static_cast<std::size_t>(c)];
          if (sc > 0) z = std::max(z, std::abs(res[e][t][c]) / sc);
        }
        if (z > o.outlier_z) worst.push_back({z, {e, t}});
      }
    std::sort(worst.begin(), worst.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    std::size_t rows = 0;
    for (const auto& ep : eps) rows += ep.size();
    worst.resize(std::min(worst.size(), rows / 100));
    const auto L = static_cast<std::size_t>(b.mode.lag);
    for (const auto& [z, at] : worst) {
      mk.bad_response[at.first][at.second] = 1;
      if (at.second >= L) mk.bad_raw[at.first][at.second - L] = 1;
    }
    fit_all();
  }
  for (std::size_t e = 0; e < eps.size(); ++e)
    for (std::size_t t = 0; t < eps[e].size(); ++t) ev.outlier_rows += (mk.bad_raw[e][t] || mk.bad_response[e][t]) ? 1 : 0;

  const Fit& B = fits[static_cast<std::size_t>(ev.best)];
  std::vector<char> used(static_cast<std::size_t>(units), 0);
  int n_used = 0;
  for (int u = 0; u < units; ++u) n_used += (used[static_cast<std::size_t>(u)] = B.unit[static_cast<std::size_t>(u)].n >= 1) ? 1 : 0;
  const double tc = t_critical(o.z, n_used - 1);
  ev.t_critical = tc;
  const auto unit_scores = [&](const std::vector<Pose6>& cv) {
    std::vector<double> s;
    for (const auto& v : cv) {
      double x = 0;
      for (int c = 0; c < kPoseDim; ++c) x += w[static_cast<std::size_t>(c)] * v[c];
      s.push_back(x);
    }
    return s;
  };
  const std::vector<double> best_scores = unit_scores(B.cv);
  // evidence, per output channel: the best mode's cross-validated prediction of that channel beats
  // ignoring the actions; the log has evidence if one channel has
  std::array<double, kPoseDim> channel_null_t{};
  for (int c = 0; c < kPoseDim; ++c) {
    std::vector<double> a, b;
    for (std::size_t u = 0; u < B.cv.size(); ++u) {
      a.push_back(B.cv[u][c]);
      b.push_back(B.cv_null[u][c]);
    }
    channel_null_t[static_cast<std::size_t>(c)] = paired(a, b, used, o.min_margin).t;
  }
  ev.null_t = *std::max_element(channel_null_t.begin(), channel_null_t.end());
  ev.evidence = ev.null_t >= tc;
  ev.plausible.assign(fits.size(), true);
  const Mode& bm = B.mode;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  ev.target_t = ev.frame_t = ev.lag_t = kInf;
  const auto group_scores = [&](const std::vector<Pose6>& cv, int g) {
    std::vector<double> out;
    for (const auto& v : cv) {
      double x = 0;
      for (int c = 3 * g; c < 3 * g + 3; ++c) x += v[c];
      out.push_back(x);
    }
    return out;
  };
  const std::array<std::vector<double>, 2> best_groups{group_scores(B.cv, 0), group_scores(B.cv, 1)};
  for (std::size_t k = 0; k < fits.size(); ++k) {
    if (static_cast<int>(k) == ev.best) continue;
    // excluded only if it predicts materially worse (by more than the margin), not merely detectably:
    // with hundreds of units a misspecified model's tiny systematic difference is "significant"
    double t = paired(best_scores, unit_scores(fits[k].cv), used, o.min_margin).t;
    // ... and only if neither group of channels (translation, rotation) says the opposite: where the
    // translations favour one hypothesis and the rotations the other, one of the two response models is
    // wrong for this log, and the log does not decide between them
    for (int g = 0; g < 2; ++g)
      if (paired(group_scores(fits[k].cv, g), best_groups[static_cast<std::size_t>(g)], used, o.min_margin).t >= tc) t = 0.0;
    ev.plausible[k] = !(t >= tc);
    const Mode& m = ev.modes[k];
    if (m.target != bm.target) ev.target_t = std::min(ev.target_t, t);
    if (m.frame != bm.frame) ev.frame_t = std::min(ev.frame_t, t);
    if (m.lag != bm.lag) ev.lag_t = std::min(ev.lag_t, t);
  }
  ev.target_resolved = ev.evidence && ev.target_t >= tc;
  ev.frame_resolved = ev.evidence && ev.frame_t >= tc;
  ev.lag_resolved = ev.evidence && ev.lag_t >= tc;

  // residuals of the best mode (noise scale for the rotation representation, misspecification)
  {
    Pose6 ss = Pose6::Zero(), cross = Pose6::Zero();
    double n = 0;
    for (std::size_t e = 0; e < eps.size(); ++e) {
      Pose6 prev = Pose6::Zero();
      bool have = false;
      for (std::size_t t = 0; t < eps[e].size(); ++t) {
        if (excluded(mk, e, t, bm)) {
          have = false;
          continue;
        }
        const Pose6 r = residual(B, B.beta, eps[e], t, o.alpha);
        ss += r.cwiseProduct(r);
        if (have) cross += r.cwiseProduct(prev);
        prev = r;
        have = true;
        n += 1;
      }
    }
    for (int c = 0; c < kPoseDim; ++c) {
      ev.residual_rms[static_cast<std::size_t>(c)] = n > 0 ? std::sqrt(ss[c] / n) : 0.0;
      ev.residual_rho[static_cast<std::size_t>(c)] = ss[c] > 0 ? cross[c] / ss[c] : 0.0;
    }
  }

  // per mode and output channel: which raw channel drives it, and whether that stands out
  struct Call {
    int raw{-1}, sign{0};
    bool routed{false};
    double t{0}, gain{0}, se{0}, explained{0};
    std::string why;
  };
  const auto call = [&](const Fit& f, int i) {
    Call c;
    std::array<double, kPoseDim> se{}, tt{};
    std::vector<std::vector<double>> loo(kPoseDim);
    for (std::size_t u = 0; u < f.loo.size(); ++u)
      if (used[u])
        for (int j = 0; j < kPoseDim; ++j) loo[static_cast<std::size_t>(j)].push_back(f.loo[u](j, i));
    int arg = 0;
    for (int j = 0; j < kPoseDim; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      se[jj] = jackknife_se(loo[jj]);
      const double b = f.beta(j, i);
      tt[jj] = se[jj] > 0 ? b / se[jj] : (b != 0 ? std::copysign(std::numeric_limits<double>::infinity(), b) : 0.0);
      if (std::abs(tt[jj]) > std::abs(tt[static_cast<std::size_t>(arg)])) arg = j;
    }
    const auto aa = static_cast<std::size_t>(arg);
    c.raw = arg;
    c.sign = f.beta(arg, i) >= 0 ? 1 : -1;
    c.t = tt[aa];
    c.gain = std::abs(f.beta(arg, i));
    c.se = se[aa];
    const double vx = f.sx2(i, arg), vy = f.vy[i];
    c.explained = vy > 0 ? std::min(1.0, c.gain * c.gain * std::max(vx, 0.0) / vy) : 0.0;
    const std::string ch = "raw channel " + std::to_string(arg);
    std::vector<int> idle;
    for (int j = 0; j < kPoseDim; ++j)
      if (excitation[static_cast<std::size_t>(j)] < o.min_excitation) idle.push_back(j);
    if (excitation[aa] < o.min_excitation || (!(std::abs(c.t) >= tc) && !idle.empty())) {
      std::string list;
      for (int j : idle) list += (list.empty() ? "" : ", ") + std::to_string(j);
      c.why = "raw channel(s) " + list + " hardly move (RMS command < " + fmt("%.3g", o.min_excitation) + ")";
      return c;
    }
    if (!(channel_null_t[static_cast<std::size_t>(i)] >= tc)) {
      c.why = "the commands do not explain its motion better than ignoring them (paired t = " + fmt("%.3g", channel_null_t[static_cast<std::size_t>(i)]) + ")";
      return c;
    }
    if (!(std::abs(c.t) >= tc)) {
      c.why = "its coefficient on " + ch + " does not stand out of its uncertainty over the log's parts (t = " + fmt("%.3g", std::abs(c.t)) + ", " +
              fmt("%.3g", tc) + " needed): the parts disagree or the motion is small; more episodes would decide";
      return c;
    }
    if (c.explained < o.min_explained) {
      c.why = ch + " explains " + std::to_string(static_cast<int>(std::lround(100 * c.explained))) +
              " % of the channel's motion: the motion is mostly not commanded (contacts, drift, a policy's reaction to them)";
      return c;
    }
    if (o.calibrated && c.gain + 2 * c.se < 0.5 / o.gain_tolerance) {
      c.why = "its response to " + ch + " is " + fmt("%.3g", c.gain) +
              "x the calibrated gain, too weak for any contract of the grammar: the motion is not driven by that command";
      return c;
    }
    for (int j = 0; j < kPoseDim; ++j) {
      if (j == arg) continue;
      std::vector<double> d;
      for (std::size_t u = 0; u < f.loo.size(); ++u)
        if (used[u]) d.push_back(c.sign * f.loo[u](arg, i) - (f.beta(j, i) >= 0 ? 1 : -1) * f.loo[u](j, i));
      const double delta = c.gain - std::abs(f.beta(j, i));
      const double s = jackknife_se(d);
      if (!(delta >= tc * s)) {
        c.why = ch + " and raw channel " + std::to_string(j) + " both explain it (their commands move together or both respond)";
        return c;
      }
    }
    // the grammar wires one raw channel to an output channel: a second raw channel that moves it at
    // more than half the first one's amplitude is a coupling (contacts, a closed loop's reactions),
    // and the wiring is not what the log shows
    double second = 0;
    int second_j = -1;
    for (int j = 0; j < kPoseDim; ++j) {
      if (j == arg) continue;
      const double amp = std::abs(f.beta(j, i)) * std::sqrt(std::max(f.sx2(i, j), 0.0));
      if (amp > second) {
        second = amp;
        second_j = j;
      }
    }
    const double first = c.gain * std::sqrt(std::max(f.sx2(i, arg), 0.0));
    if (second_j >= 0 && second > o.max_coupling * first) {
      c.why = "raw channel " + std::to_string(second_j) + " moves it at " + fmt("%.3g", second / std::max(first, 1e-300)) + "x the amplitude " + ch +
              " does: the channels are coupled (contacts, a closed loop's reactions), not wired one to one";
      return c;
    }
    c.routed = true;
    return c;
  };
  std::array<std::vector<Call>, kPoseDim> calls;
  for (std::size_t k = 0; k < fits.size(); ++k)
    for (int i = 0; i < kPoseDim; ++i)
      calls[static_cast<std::size_t>(i)].push_back(ev.plausible[k] ? call(fits[k], i) : Call{});
  for (int i = 0; i < kPoseDim; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    const Call& b = calls[ii][static_cast<std::size_t>(ev.best)];
    ChannelCall& out = ev.channel[ii];
    out.raw = b.raw;
    out.sign = b.sign;
    out.t = b.t;
    out.gain = b.gain;
    out.gain_se = b.se;
    out.explained = b.explained;
    if (!ev.evidence) {
      out.why = "the logged actions do not explain the logged motion better than no actions at all";
      continue;
    }
    if (!b.routed) {
      out.why = b.why;
      continue;
    }
    bool routed = true, signed_ = true;
    for (std::size_t k = 0; k < fits.size() && routed; ++k) {
      if (!ev.plausible[k] || static_cast<int>(k) == ev.best) continue;
      const Call& c = calls[ii][k];
      if (!c.routed || c.raw != b.raw) {
        routed = false;
        out.why = "under " + mode_words(ev.modes[k]) + ", which the log cannot exclude, " +
                  (c.routed ? "it reads raw channel " + std::to_string(c.raw) : c.why);
      } else if (c.sign != b.sign && signed_) {
        signed_ = false;
        out.why = "its sign differs under " + mode_words(ev.modes[k]) + ", which the log cannot exclude";
      }
    }
    out.routed = routed;
    out.sign_committed = routed && signed_;
  }
  // a raw channel drives one output channel: a committed channel whose raw channel also explains a
  // large share of another output channel's motion (more than --max-coupling of the share it explains
  // here) is a coupling (pulling the cube towards the base tilts the tool), and is not committed
  for (int i = 0; i < kPoseDim; ++i) {
    auto& a = ev.channel[static_cast<std::size_t>(i)];
    if (!a.routed) continue;
    for (int k = 0; k < kPoseDim; ++k) {
      if (k == i || !(B.vy[k] > 0)) continue;
      const double share = std::pow(B.beta(a.raw, k), 2) * std::max(B.sx2(k, a.raw), 0.0) / B.vy[k];
      if (share > o.max_coupling * a.explained) {
        a.routed = a.sign_committed = false;
        a.why = "raw channel " + std::to_string(a.raw) + " also explains " + fmt("%.3g", 100 * share) + " % of output channel " + kChannel[k] +
                "'s motion (" + fmt("%.3g", 100 * a.explained) + " % of this one's): a coupling, not a wiring one to one";
        break;
      }
    }
  }
  // a permutation reads each raw channel once: a channel whose read raw channel drives another output
  // channel more strongly (a physical coupling: pulling down turns the tool) is not committed
  for (int i = 0; i < kPoseDim; ++i)
    for (int k = 0; k < kPoseDim; ++k) {
      auto& a = ev.channel[static_cast<std::size_t>(i)];
      const auto& b = ev.channel[static_cast<std::size_t>(k)];
      if (i == k || !a.routed || b.raw != a.raw || std::abs(b.t) <= std::abs(a.t)) continue;
      a.routed = a.sign_committed = false;
      a.why = "raw channel " + std::to_string(a.raw) + " drives output channel " + kChannel[k] + " more strongly (a coupling, or " + kChannel[k] +
              " reads it)";
    }
  for (int i = 0; i < kPoseDim; ++i)
    for (int k = i + 1; k < kPoseDim; ++k) {
      auto& a = ev.channel[static_cast<std::size_t>(i)];
      auto& b = ev.channel[static_cast<std::size_t>(k)];
      if (a.routed && b.routed && a.raw == b.raw) {
        a.routed = b.routed = a.sign_committed = b.sign_committed = false;
        a.why = b.why = std::string("output channels ") + kChannel[i] + " and " + kChannel[k] + " both read raw channel " + std::to_string(a.raw);
      }
    }
  // the best mode's most likely permutation (largest Σ|t|), signs and gains
  {
    std::array<std::array<double, kPoseDim>, kPoseDim> at{};
    std::vector<std::vector<double>> loo(kPoseDim * kPoseDim);
    for (std::size_t u = 0; u < B.loo.size(); ++u)
      if (used[u])
        for (int i = 0; i < kPoseDim; ++i)
          for (int j = 0; j < kPoseDim; ++j) loo[static_cast<std::size_t>(i * kPoseDim + j)].push_back(B.loo[u](j, i));
    for (int i = 0; i < kPoseDim; ++i)
      for (int j = 0; j < kPoseDim; ++j) {
        const double s = jackknife_se(loo[static_cast<std::size_t>(i * kPoseDim + j)]);
        at[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = std::abs(B.beta(j, i)) / std::max(s, 1e-300);
      }
    std::array<int, kPoseDim> p{0, 1, 2, 3, 4, 5};
    double best = -1;
    do {
      double s = 0;
      bool fits_commits = true;
      for (int i = 0; i < kPoseDim; ++i) {
        const auto& c = ev.channel[static_cast<std::size_t>(i)];
        if (c.routed && p[static_cast<std::size_t>(i)] != c.raw) fits_commits = false;
        s += std::min(at[static_cast<std::size_t>(i)][static_cast<std::size_t>(p[static_cast<std::size_t>(i)])], 1e12);
      }
      if (fits_commits && s > best) {
        best = s;
        ev.map_perm = p;
      }
    } while (std::next_permutation(p.begin(), p.end()));
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      const double b = B.beta(ev.map_perm[ii], i);
      ev.map_sign[ii] = b >= 0 ? 1 : -1;
      ev.map_gain[ii] = std::abs(b);
    }
  }
  return ev;
}

}  // namespace actionshift::selftest::detail
