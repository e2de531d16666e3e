#include "actionshift/adapt/probe_selector.hpp"

#include "actionshift/core/transforms.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace actionshift::adapt {

int active_set(const Eigen::Ref<const Eigen::VectorXd>& p, int max_active, double mass, std::span<int> order,
               std::span<int> out) {
  const int k = std::min(std::max(1, max_active), static_cast<int>(p.size()));
  if (order.size() != static_cast<std::size_t>(p.size()) || out.size() < static_cast<std::size_t>(k))
    throw std::invalid_argument("active_set: scratch or output too small");
  std::iota(order.begin(), order.end(), 0);
  // the k largest probabilities, ties by index: the order a stable sort by decreasing p gives
  std::partial_sort(order.begin(), order.begin() + k, order.end(),
                    [&](int x, int y) { return p[x] > p[y] || (p[x] == p[y] && x < y); });
  int n = 0;
  double covered = 0;
  for (int i = 0; i < k; ++i) {
    if (n > 0 && covered >= mass) break;
    const int h = order[static_cast<std::size_t>(i)];
    out[static_cast<std::size_t>(n++)] = h;
    covered += p[h];
  }
  std::sort(out.begin(), out.begin() + n);
  return n;
}

ProbeSelector::ProbeSelector(int pool_size, int max_active, int window)
    : pool_size_(pool_size), max_active_(std::min(max_active, pool_size)), window_(window) {
  if (pool_size < 1 || max_active < 1 || window < 0)
    throw std::invalid_argument("probe selector needs a pool, max_active >= 1 and window >= 0 (got " +
                                std::to_string(pool_size) + ", " + std::to_string(max_active) + ", " +
                                std::to_string(window) + ")");
  const auto m = static_cast<Eigen::Index>(max_active_);
  order_.resize(static_cast<std::size_t>(pool_size));
  active_.resize(static_cast<std::size_t>(max_active_));
  p_all_.resize(pool_size);
  p_.resize(m);
  logp_.resize(m);
  S_.resize(m, kPoseDim);
  O_.resize(m, kPoseDim);
  motion_.resize(m);
  buf_.resize(static_cast<std::size_t>(2 * m * m));
  sums_.resize(m);
  max_.resize(m);
  weighted_.resize(m);
  post_.resize(m);
  if (window > 0) {
    Et_.resize(m, m);
    raw_.resize(kPoseDim, window);
    Y_.resize(kPoseDim * m, window);
    acc_.resize(window);
  }
}

void ProbeSelector::select_active(const PoolBelief& b, int max_active, double mass) {
  if (b.size() != pool_size_) throw std::invalid_argument("probe selector: belief has a different pool size");
  p_all_ = b.log_probs().array().exp();
  n_ = active_set(p_all_, std::min(max_active, max_active_), mass, order_, active_);
  mass_ = 0;
  for (int j = 0; j < n_; ++j) {
    const int h = active_[static_cast<std::size_t>(j)];
    p_[j] = p_all_[h];
    logp_[j] = b.log_probs()[h];
    mass_ += p_[j];
  }
}

void ProbeSelector::set_active(const PoolBelief& b, std::span<const int> active) {
  if (b.size() != pool_size_) throw std::invalid_argument("probe selector: belief has a different pool size");
  if (active.empty() || static_cast<int>(active.size()) > max_active_)
    throw std::invalid_argument("probe selector: active set must have 1.." + std::to_string(max_active_) + " members");
  p_all_ = b.log_probs().array().exp();
  n_ = static_cast<int>(active.size());
  mass_ = 0;
  for (int j = 0; j < n_; ++j) {
    const int h = active[static_cast<std::size_t>(j)];
    if (h < 0 || h >= pool_size_) throw std::invalid_argument("probe selector: hypothesis index out of range");
    active_[static_cast<std::size_t>(j)] = h;
    p_[j] = p_all_[h];
    logp_[j] = b.log_probs()[h];
    mass_ += p_[j];
  }
}

void ProbeSelector::predict(const PoolBelief& b, const Action& c, const Mat3& R, bool calibrated, bool lag_aware,
                            bool motion) {
  const ResponseModel& m = b.model();
  double w[kPoseDim], inv_sigma[kPoseDim];
  for (int ch = 0; ch < kPoseDim; ++ch) {
    const auto k = static_cast<std::size_t>(ch);
    w[ch] = m.alpha[k] / m.sigma[k];
    inv_sigma[ch] = 1.0 / m.sigma[k];
  }
  for (int j = 0; j < n_; ++j) {
    const Decoder& rep = b.replica(active_[static_cast<std::size_t>(j)]);
    const Action pred = lag_aware ? rep.preview(c, R) : actionshift::decode(rep.contract(), c, R, rep.tracked_target());
    for (int ch = 0; ch < kPoseDim; ++ch) S_(j, ch) = w[ch] * pred[ch];
    if (!calibrated)
      for (int ch = 0; ch < kPoseDim; ++ch) O_(j, ch) = inv_sigma[ch] * pred[ch];
    if (motion) motion_[j] = m.expected(pred).norm();
  }
}

void ProbeSelector::posteriors(bool calibrated) {
  const Eigen::Index n = n_;
  Eigen::Map<Eigen::ArrayXXd> T(buf_.data(), n, n), E(buf_.data() + n * n, n, n);
  const Cols6& O = calibrated ? S_ : O_;
  const auto s = S_.topRows(n).array();
  const auto logp = logp_.head(n).array();
  // column h: h's simulated observation; row j: −½ (squared distance to j's mean) + log p_j
  for (Eigen::Index h = 0; h < n; ++h)
    T.col(h) = logp - 0.5 * ((s.col(0) - O(h, 0)).square() + (s.col(1) - O(h, 1)).square() + (s.col(2) - O(h, 2)).square() +
                             (s.col(3) - O(h, 3)).square() + (s.col(4) - O(h, 4)).square() + (s.col(5) - O(h, 5)).square());
  max_.head(n) = T.colwise().maxCoeff().transpose();
  T.rowwise() -= max_.head(n).transpose().array();
  E = T.exp();
  sums_.head(n) = E.colwise().sum().transpose();
  weighted_.head(n) = (E * T).colwise().sum().transpose();
}

double ProbeSelector::expected_entropy(const PoolBelief& b, const Action& candidate, const Mat3& R, bool calibrated,
                                       bool lag_aware, double* motion) {
  predict(b, candidate, R, calibrated, lag_aware, motion != nullptr);
  posteriors(calibrated);
  double eh = 0;
  for (int h = 0; h < n_; ++h) {
    // −Σ q ln q of the posterior q_j = e_j / Σe with ln q_j = t_j − ln Σe
    const double ent = std::log(sums_[h]) - weighted_[h] / sums_[h];
    eh += p_[h] / mass_ * ent;
  }
  if (motion) {
    double mo = 0;
    for (int h = 0; h < n_; ++h) mo += p_[h] / mass_ * motion_[h];
    *motion = mo;
  }
  return eh;
}

void ProbeSelector::compute_task_error(const PoolBelief& b, std::span<const Action> recent, const Mat3& R) {
  const int w = static_cast<int>(recent.size());
  if (w < 1 || w > window_) throw std::invalid_argument("probe selector: recent window must have 1.." + std::to_string(window_) + " intents");
  const Mat3 Rt = R.transpose();
  // what each hypothesis j must decode for every intent to be executed exactly, on j's side of its
  // frame rotation: decode_j(raw) − a = R_j (G_j raw − R_jᵀ (a + target_j)) with R_j = R (tool) or I
  for (int j = 0; j < n_; ++j) {
    const Decoder& rep = b.replica(active_[static_cast<std::size_t>(j)]);
    const Contract& c = rep.contract();
    const Pose6 tgt = rep.tracked_target();
    for (int k = 0; k < w; ++k) {
      Pose6 v = recent[static_cast<std::size_t>(k)].head<kPoseDim>();
      if (c.target() == Target::kAbsolute) v += tgt;
      if (c.frame() == Frame::kTool) {
        v.head<3>() = Rt * v.head<3>().eval();
        v.tail<3>() = Rt * v.tail<3>().eval();
      }
      for (int ch = 0; ch < kPoseDim; ++ch) Y_(kPoseDim * j + ch, k) = v[ch];
    }
  }
  const double inv_w = 1.0 / static_cast<double>(w);
  for (int i = 0; i < n_; ++i) {
    const Decoder& ri = b.replica(active_[static_cast<std::size_t>(i)]);
    const Pose6 tgt = ri.tracked_target();
    for (int k = 0; k < w; ++k)
      raw_.col(k) = actionshift::encode(ri.contract(), recent[static_cast<std::size_t>(k)], R, tgt).head<kPoseDim>();
    const auto raw = raw_.leftCols(w).array();
    for (int j = 0; j < n_; ++j) {
      if (j == i) {
        Et_(j, i) = 0.0;
        continue;
      }
      const Contract& cj = b.replica(active_[static_cast<std::size_t>(j)]).contract();
      const auto& p = cj.permutation();
      const auto& g = cj.gain();
      const auto y = Y_.middleRows(kPoseDim * j, kPoseDim).leftCols(w).array();
      acc_.head(w) = (g[0] * raw.row(p[0]) - y.row(0)).square() + (g[1] * raw.row(p[1]) - y.row(1)).square() +
                     (g[2] * raw.row(p[2]) - y.row(2)).square() + (g[3] * raw.row(p[3]) - y.row(3)).square() +
                     (g[4] * raw.row(p[4]) - y.row(4)).square() + (g[5] * raw.row(p[5]) - y.row(5)).square();
      Et_(j, i) = acc_.head(w).sqrt().sum() * inv_w;
    }
  }
}

void ProbeSelector::set_task_error(const Eigen::MatrixXd& E) {
  if (E.rows() != n_ || E.cols() != n_) throw std::invalid_argument("probe selector: task error must be n x n over the active set");
  if (window_ < 1) throw std::invalid_argument("probe selector: built without a DualABI window");
  Et_.topLeftCorner(n_, n_) = E.transpose();
}

Eigen::MatrixXd ProbeSelector::task_error() const { return Et_.topLeftCorner(n_, n_).transpose(); }

double ProbeSelector::regret_of_column(int h) {
  const Eigen::Index n = n_;
  const Eigen::Map<const Eigen::ArrayXXd> E(buf_.data() + n * n, n, n);
  post_.head(n) = E.col(h) / sums_[h];
  Eigen::Index best = 0;
  for (Eigen::Index i = 1; i < n; ++i)
    if (post_[i] > post_[best]) best = i;
  return Et_.col(best).head(n).dot(post_.head(n));
}

double ProbeSelector::current_regret() {
  const Eigen::Index n = n_;
  post_.head(n) = p_.head(n) / p_.head(n).sum();
  Eigen::Index best = 0;
  for (Eigen::Index i = 1; i < n; ++i)
    if (post_[i] > post_[best]) best = i;
  return Et_.col(best).head(n).dot(post_.head(n));
}

double ProbeSelector::expected_future_regret(const PoolBelief& b, const Action& candidate, const Mat3& R, bool calibrated,
                                             bool lag_aware) {
  predict(b, candidate, R, calibrated, lag_aware, false);
  posteriors(calibrated);
  const double mass = p_.head(n_).sum();
  double ef = 0;
  for (int h = 0; h < n_; ++h) ef += p_[h] / mass * regret_of_column(h);
  return ef;
}

}  // namespace actionshift::adapt
