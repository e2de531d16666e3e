#include "actionshift/adapt/probe_selector.hpp"

#include "actionshift/core/transforms.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace actionshift::adapt {

namespace {

// The hot loops run on four-lane vectors (GCC/Clang vector extensions) and are compiled twice,
// for AVX2 and for baseline x86-64, the binary choosing at load time (target_clones). Every lane
// sees the same IEEE operations in the same order in both versions (no fused multiply-add:
// AVX2 does not imply FMA and the project compiles in ISO mode, -ffp-contract=off), so both
// give the same bits, and the results do not depend on the vector width.
constexpr int kLanes = 4;
typedef double V __attribute__((vector_size(32)));
typedef long long VI __attribute__((vector_size(32)));
typedef double VU __attribute__((vector_size(32), aligned(8), may_alias));  // unaligned access

// (ACTIONSHIFT_NO_TARGET_CLONES builds the baseline version only, to compare the two)
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(__SANITIZE_ADDRESS__) && \
    !defined(ACTIONSHIFT_NO_TARGET_CLONES)
#define ACTIONSHIFT_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define ACTIONSHIFT_CLONES
#endif

// (macros rather than functions: a function taking or returning a 32-byte vector has a different
// ABI in the two versions)
#define VLOAD(p) (*reinterpret_cast<const VU*>(p))
#define VSTORE(p, v) (*reinterpret_cast<VU*>(p) = (v))
#define VSPLAT(x) (V{(x), (x), (x), (x)})

// Below this exponent the kernel's exp is exactly 0: exp(−708) ≈ 3.3e−308 is the smallest value it
// forms as a normal number, and a posterior numerator below it is < 2⁻¹⁰²¹ of the column's largest
// (which is 1), far below a sum's rounding.
constexpr double kExpCutoff = -708.0;

// exp(x) for x ≤ 0 by the Cephes rational approximation exactly as Eigen 3.4's pexp evaluates it
// without FMA (the same constants and operation order; its 2ⁿ scaling is exact in the normal
// range, as here), so the two agree bit for bit on [−708, 0]; 0 below −708.
#define ACTIONSHIFT_EXP_BODY(x, out)                                                              \
  do {                                                                                            \
    const V magic = VSPLAT(6755399441055744.0); /* 1.5 · 2^52: adding it rounds to an integer */  \
    V fx = (x) * VSPLAT(1.4426950408889634073599) + VSPLAT(0.5);                                    \
    V r = (fx + magic) - magic;                                                                   \
    r = r - ((r > fx) ? VSPLAT(1.0) : VSPLAT(0.0)); /* floor */                                    \
    const VI bits = (reinterpret_cast<VI>(r + VSPLAT(6755399441055744.0 + 1023.0)) -               \
                     reinterpret_cast<VI>(magic)) << 52;                                          \
    V g = (x) - r * VSPLAT(0.693145751953125);                                                     \
    g = g - r * VSPLAT(1.42860682030941723212e-6);                                                 \
    const V g2 = g * g;                                                                           \
    V px = VSPLAT(1.26177193074810590878e-4) * g2 + VSPLAT(3.02994407707441961300e-2);              \
    px = px * g2 + VSPLAT(9.99999999999999999910e-1);                                              \
    px = px * g;                                                                                  \
    V qx = VSPLAT(3.00198505138664455042e-6) * g2 + VSPLAT(2.52448340349684104192e-3);              \
    qx = qx * g2 + VSPLAT(2.27265548208155028766e-1);                                              \
    qx = qx * g2 + VSPLAT(2.00000000000000000009e0);                                               \
    V y = px / (qx - px);                                                                         \
    y = VSPLAT(2.0) * y + VSPLAT(1.0);                                                              \
    (out) = ((x) < VSPLAT(kExpCutoff)) ? VSPLAT(0.0) : y * reinterpret_cast<V>(bits);              \
  } while (0)

// Row j, lane h of `buf` (ld lanes per row, rows j < n): first the log-numerator
// t(j, h) = log p_j − ½ Σ_ch (o_ch,h − s_ch,j)² (channels summed 0..5), with max[h] = max_j t(j, h);
// then e = exp(t − max[h]) in place, sums[h] = Σ_j e and weighted[h] = Σ_j e·(t − max[h]), summed
// in row order. s and o hold kPoseDim rows of ld lanes.
ACTIONSHIFT_CLONES
void posterior_kernel(int n, int ld, const double* __restrict s, const double* __restrict o,
                      const double* __restrict logp, double* __restrict buf, double* __restrict max,
                      double* __restrict sums, double* __restrict weighted) {
  for (int j = 0; j < n; ++j) {
    const V lp = VSPLAT(logp[j]);
    double* row = buf + static_cast<std::ptrdiff_t>(j) * ld;
    for (int h = 0; h < ld; h += kLanes) {
      V d = VLOAD(o + h) - s[j];
      V acc = d * d;
      for (int ch = 1; ch < kPoseDim; ++ch) {
        d = VLOAD(o + ch * ld + h) - s[ch * ld + j];
        acc = acc + d * d;
      }
      const V t = lp - VSPLAT(0.5) * acc;
      VSTORE(row + h, t);
      if (j == 0) {
        VSTORE(max + h, t);
      } else {
        const V m = VLOAD(max + h);
        VSTORE(max + h, t > m ? t : m);
      }
    }
  }
  for (int j = 0; j < n; ++j) {
    double* row = buf + static_cast<std::ptrdiff_t>(j) * ld;
    for (int h = 0; h < ld; h += kLanes) {
      const V x = VLOAD(row + h) - VLOAD(max + h);
      V e;
      ACTIONSHIFT_EXP_BODY(x, e);
      VSTORE(row + h, e);
      if (j == 0) {
        VSTORE(sums + h, e);
        VSTORE(weighted + h, e * x);
      } else {
        VSTORE(sums + h, VLOAD(sums + h) + e);
        VSTORE(weighted + h, VLOAD(weighted + h) + e * x);
      }
    }
  }
}

// DualABI: for every lane h of the exponentiated array, the posterior q(j) = e(j, h) / sums[h]
// (written to `q`), its MAP (the first largest) and regret[h] = Σ_j Et(j, MAP) q(j), with Et
// column-major (ldE rows)
ACTIONSHIFT_CLONES
void regret_kernel(int n, int ld, const double* __restrict buf, const double* __restrict sums, const double* __restrict Et,
                   int ldE, double* __restrict q, double* __restrict regret) {
  for (int h = 0; h < ld; h += kLanes) {
    const V sum = VLOAD(sums + h);
    V best_q = VLOAD(buf + h) / sum;
    VSTORE(q + h, best_q);
    V best = VSPLAT(0.0);
    for (int j = 1; j < n; ++j) {
      const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(j) * ld + h;
      const V qj = VLOAD(buf + at) / sum;
      VSTORE(q + at, qj);
      const VI better = qj > best_q;
      best_q = better ? qj : best_q;
      best = better ? VSPLAT(static_cast<double>(j)) : best;
    }
    const double* col[kLanes];
    for (int l = 0; l < kLanes; ++l) col[l] = Et + static_cast<std::ptrdiff_t>(best[l]) * ldE;
    V acc = VSPLAT(0.0);
    for (int j = 0; j < n; ++j) {
      const V e = V{col[0][j], col[1][j], col[2][j], col[3][j]};
      acc = acc + e * VLOAD(q + static_cast<std::ptrdiff_t>(j) * ld + h);
    }
    VSTORE(regret + h, acc);
  }
}

// DualABI: the squared decode error of hypothesis i's encoding of the window under every
// hypothesis j, sq(j, k) = Σ_ch (g_j,ch · raw(p_j,ch, k) − y_j(ch, k))² (channels summed 0..5), for
// rows j < n and ldw lanes k; raw holds kPoseDim rows, Y kPoseDim rows per hypothesis, of ldw lanes
ACTIONSHIFT_CLONES
void task_error_kernel(int n, int ldw, const double* __restrict raw, const double* __restrict Y,
                       const double* __restrict gain, const int* __restrict perm, double* __restrict sq) {
  for (int j = 0; j < n; ++j) {
    const double* y = Y + static_cast<std::ptrdiff_t>(j) * kPoseDim * ldw;
    const double* g = gain + kPoseDim * j;
    const int* p = perm + kPoseDim * j;
    double* out = sq + static_cast<std::ptrdiff_t>(j) * ldw;
    for (int k = 0; k < ldw; k += kLanes) {
      V d = g[0] * VLOAD(raw + p[0] * ldw + k) - VLOAD(y + k);
      V acc = d * d;
      for (int ch = 1; ch < kPoseDim; ++ch) {
        d = g[ch] * VLOAD(raw + p[ch] * ldw + k) - VLOAD(y + ch * ldw + k);
        acc = acc + d * d;
      }
      VSTORE(out + k, acc);
    }
  }
}

}  // namespace
#undef VLOAD
#undef VSTORE
#undef VSPLAT
#undef ACTIONSHIFT_EXP_BODY
#undef ACTIONSHIFT_CLONES

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
    : pool_size_(pool_size),
      max_active_(std::min(max_active, pool_size)),
      window_(window),
      ld_((std::max(max_active_, 1) + kLanes - 1) / kLanes * kLanes) {
  if (pool_size < 1 || max_active < 1 || window < 0)
    throw std::invalid_argument("probe selector needs a pool, max_active >= 1 and window >= 0 (got " +
                                std::to_string(pool_size) + ", " + std::to_string(max_active) + ", " +
                                std::to_string(window) + ")");
  const auto m = static_cast<Eigen::Index>(max_active_);
  const auto lanes = static_cast<std::size_t>(ld_);
  order_.resize(static_cast<std::size_t>(pool_size));
  active_.resize(static_cast<std::size_t>(max_active_));
  p_all_.resize(pool_size);
  p_.resize(m);
  logp_.assign(lanes, 0.0);
  // the lanes past n are computed and ignored; zeros keep them finite
  S_.assign(kPoseDim * lanes, 0.0);
  O_.assign(kPoseDim * lanes, 0.0);
  motion_.resize(m);
  buf_.assign(static_cast<std::size_t>(m) * lanes, 0.0);
  if (window > 0) q_.assign(static_cast<std::size_t>(m) * lanes, 0.0);
  sums_.assign(lanes, 0.0);
  max_.assign(lanes, 0.0);
  weighted_.assign(lanes, 0.0);
  regret_.assign(lanes, 0.0);
  post_.resize(m);
  if (window > 0) {
    Et_.resize(m, m);
    ldw_ = (window + kLanes - 1) / kLanes * kLanes;
    const auto lw = static_cast<std::size_t>(ldw_);
    raw_.assign(kPoseDim * lw, 0.0);
    Y_.assign(kPoseDim * static_cast<std::size_t>(m) * lw, 0.0);
    sq_.assign(static_cast<std::size_t>(m) * lw, 0.0);
    gain_.assign(kPoseDim * static_cast<std::size_t>(m), 0.0);
    perm_.assign(kPoseDim * static_cast<std::size_t>(m), 0);
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
    logp_[static_cast<std::size_t>(j)] = b.log_probs()[h];
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
    logp_[static_cast<std::size_t>(j)] = b.log_probs()[h];
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
    for (int ch = 0; ch < kPoseDim; ++ch) S_[static_cast<std::size_t>(ch * ld_ + j)] = w[ch] * pred[ch];
    if (!calibrated)
      for (int ch = 0; ch < kPoseDim; ++ch) O_[static_cast<std::size_t>(ch * ld_ + j)] = inv_sigma[ch] * pred[ch];
    if (motion) motion_[j] = m.expected(pred).norm();
  }
}

void ProbeSelector::posteriors(bool calibrated) {
  posterior_kernel(n_, ld_, S_.data(), calibrated ? S_.data() : O_.data(), logp_.data(), buf_.data(), max_.data(),
                   sums_.data(), weighted_.data());
}

Eigen::MatrixXd ProbeSelector::last_posteriors() const {
  Eigen::MatrixXd q(n_, n_);
  for (int h = 0; h < n_; ++h)
    for (int j = 0; j < n_; ++j)
      q(j, h) = buf_[static_cast<std::size_t>(j * ld_ + h)] / sums_[static_cast<std::size_t>(h)];
  return q;
}

double ProbeSelector::expected_entropy(const PoolBelief& b, const Action& candidate, const Mat3& R, bool calibrated,
                                       bool lag_aware, double* motion) {
  predict(b, candidate, R, calibrated, lag_aware, motion != nullptr);
  posteriors(calibrated);
  double eh = 0;
  for (int h = 0; h < n_; ++h) {
    // −Σ q ln q of the posterior q_j = e_j / Σe with ln q_j = t_j − ln Σe
    const auto l = static_cast<std::size_t>(h);
    const double ent = std::log(sums_[l]) - weighted_[l] / sums_[l];
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
      for (int ch = 0; ch < kPoseDim; ++ch) Y_[static_cast<std::size_t>((kPoseDim * j + ch) * ldw_ + k)] = v[ch];
    }
  }
  for (int j = 0; j < n_; ++j) {
    const Contract& cj = b.replica(active_[static_cast<std::size_t>(j)]).contract();
    for (int ch = 0; ch < kPoseDim; ++ch) {
      const auto l = static_cast<std::size_t>(kPoseDim * j + ch);
      gain_[l] = cj.gain()[static_cast<std::size_t>(ch)];
      perm_[l] = cj.permutation()[static_cast<std::size_t>(ch)];
    }
  }
  const double inv_w = 1.0 / static_cast<double>(w);
  Eigen::Map<Eigen::ArrayXd> sq(sq_.data(), static_cast<Eigen::Index>(n_) * ldw_);
  for (int i = 0; i < n_; ++i) {
    const Decoder& ri = b.replica(active_[static_cast<std::size_t>(i)]);
    const Pose6 tgt = ri.tracked_target();
    for (int k = 0; k < w; ++k) {
      const Action raw = actionshift::encode(ri.contract(), recent[static_cast<std::size_t>(k)], R, tgt);
      for (int ch = 0; ch < kPoseDim; ++ch) raw_[static_cast<std::size_t>(ch * ldw_ + k)] = raw[ch];
    }
    task_error_kernel(n_, ldw_, raw_.data(), Y_.data(), gain_.data(), perm_.data(), sq_.data());
    sq = sq.sqrt();
    for (int j = 0; j < n_; ++j) {
      const double* row = sq_.data() + static_cast<std::ptrdiff_t>(j) * ldw_;
      double sum = 0;
      for (int k = 0; k < w; ++k) sum += row[k];
      Et_(j, i) = j == i ? 0.0 : sum * inv_w;
    }
  }
}

void ProbeSelector::set_task_error(const Eigen::MatrixXd& E) {
  if (E.rows() != n_ || E.cols() != n_) throw std::invalid_argument("probe selector: task error must be n x n over the active set");
  if (window_ < 1) throw std::invalid_argument("probe selector: built without a DualABI window");
  Et_.topLeftCorner(n_, n_) = E.transpose();
}

Eigen::MatrixXd ProbeSelector::task_error() const { return Et_.topLeftCorner(n_, n_).transpose(); }

double ProbeSelector::current_regret() {
  if (window_ < 1) throw std::logic_error("probe selector: built without a DualABI window");
  const Eigen::Index n = n_;
  post_.head(n) = p_.head(n) / p_.head(n).sum();
  Eigen::Index best = 0;
  for (Eigen::Index i = 1; i < n; ++i)
    if (post_[i] > post_[best]) best = i;
  return Et_.col(best).head(n).dot(post_.head(n));
}

double ProbeSelector::expected_future_regret(const PoolBelief& b, const Action& candidate, const Mat3& R, bool calibrated,
                                             bool lag_aware) {
  if (window_ < 1) throw std::logic_error("probe selector: built without a DualABI window");
  predict(b, candidate, R, calibrated, lag_aware, false);
  posteriors(calibrated);
  regret_kernel(n_, ld_, buf_.data(), sums_.data(), Et_.data(), static_cast<int>(Et_.rows()), q_.data(), regret_.data());
  const double mass = p_.head(n_).sum();
  double ef = 0;
  for (int h = 0; h < n_; ++h) ef += p_[h] / mass * regret_[static_cast<std::size_t>(h)];
  return ef;
}

}  // namespace actionshift::adapt
