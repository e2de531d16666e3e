// The probe selector's vectorised kernel (src/adapt/probe_selector.cpp: the lane layout, its own
// exp, exactly 0 below −708) against a plain re-computation of the same quantities with std::exp,
// one posterior at a time (the same distance arithmetic): every posterior entry within 1e-12 relative (an entry the kernel rounds
// to 0 must be below 1e-300), the expected entropy and DualABI's expected regret within 1e-12.
// The beliefs range from uniform to so sharp that many log-weights lie below −708, and the test
// checks that both the cutoff and the range just above it are exercised, so a cutoff moved to where
// it changes a posterior by more than 1e-12 of its value fails here.
#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/probe_selector.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/transforms.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "synthetic.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace actionshift::adapt {
namespace {

struct Reference {
  Eigen::MatrixXd q;  // column h: posterior after observing h's prediction
  double entropy{0}, regret{0};
};

// the textbook computation: one posterior vector at a time, std::exp, sums in index order
Reference reference(const PoolBelief& b, std::span<const int> active, const Action& c, const Mat3& R, bool calibrated,
                    bool lag_aware, const Eigen::MatrixXd& E, int* flushed, int* deep) {
  const int n = static_cast<int>(active.size());
  const ResponseModel& m = b.model();
  std::vector<Pose6> s(static_cast<std::size_t>(n)), o(static_cast<std::size_t>(n));
  Eigen::VectorXd logp(n), p(n);
  double mass = 0;
  for (int j = 0; j < n; ++j) {
    const int a = active[static_cast<std::size_t>(j)];
    const Decoder& rep = b.replica(a);
    const Action pred = lag_aware ? rep.preview(c, R) : decode(rep.contract(), c, R, rep.tracked_target());
    for (int ch = 0; ch < kPoseDim; ++ch) {
      const auto k = static_cast<std::size_t>(ch);
      s[static_cast<std::size_t>(j)][ch] = m.alpha[k] / m.sigma[k] * pred[ch];
      o[static_cast<std::size_t>(j)][ch] = calibrated ? s[static_cast<std::size_t>(j)][ch] : 1.0 / m.sigma[k] * pred[ch];
    }
    logp[j] = b.log_probs()[a];
    p[j] = std::exp(logp[j]);
    mass += p[j];
  }
  Reference out;
  out.q.resize(n, n);
  Eigen::VectorXd t(n);
  for (int h = 0; h < n; ++h) {
    for (int j = 0; j < n; ++j) {
      // channels summed in order, as the selector does (a log-weight of −5000 carries an absolute
      // rounding of 1e-12, which a different summation order would turn into 1e-12 of its exp)
      double d2 = 0;
      for (int ch = 0; ch < kPoseDim; ++ch) {
        const double d = s[static_cast<std::size_t>(j)][ch] - o[static_cast<std::size_t>(h)][ch];
        d2 += d * d;
      }
      t[j] = logp[j] - 0.5 * d2;
    }
    const double mx = t.maxCoeff();
    double z = 0, w = 0;
    for (int j = 0; j < n; ++j) {
      const double x = t[j] - mx;
      if (x < -708) ++*flushed;
      else if (x < -30) ++*deep;
      const double e = std::exp(x);
      out.q(j, h) = e;
      z += e;
      w += e * x;
    }
    out.q.col(h) /= z;
    out.entropy += p[h] / mass * (std::log(z) - w / z);
    Eigen::Index best = 0;
    for (Eigen::Index j = 1; j < n; ++j)
      if (out.q(j, h) > out.q(best, h)) best = j;
    out.regret += p[h] / mass * E.row(best).dot(out.q.col(h));
  }
  return out;
}

Mat3 rotation(Rng& rng) {
  const Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
  return q.normalized().toRotationMatrix();
}

bool near(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(1.0, std::abs(b)); }

TEST(ProbeSelectorKernel, PosteriorsEntropyAndRegretMatchAPlainComputation) {
  Rng rng(20261123);
  int flushed = 0, deep = 0, compared = 0;
  for (const char* pool_name : {"reference9", "full"}) {
    const std::vector<Contract> pool = data::resolve_manifest(pool_name).contracts();
    const auto H = static_cast<int>(pool.size());
    // sharpness: the pick-like noise, then 10× and 50× smaller (log-weights far below −708)
    for (const double sharp : {1.0, 10.0, 50.0}) {
      ResponseModel model = testing::pick_like();
      for (auto& sg : model.sigma) sg /= sharp;
      const Contract truth = pool[static_cast<std::size_t>(rng.uniform_int(pool.size()))];
      for (const int updates : {0, 1, 4}) {
        PoolBelief b(pool, model);
        Decoder env(truth);
        const Mat3 R = rotation(rng);
        for (int k = 0; k < updates; ++k) {
          const Action raw = testing::intent(k);
          Pose6 obs = model.expected(env.step(raw, R));
          for (int ch = 0; ch < kPoseDim; ++ch) obs[ch] += model.sigma[static_cast<std::size_t>(ch)] * rng.normal();
          b.update(raw, obs, R);
        }
        ProbeSelector sel(H, 32, 8);
        sel.select_active(b, 32, 1.0 - 1e-9);
        const int n = sel.num_active();
        const std::vector<int> active(sel.active().begin(), sel.active().end());
        Eigen::MatrixXd E(n, n);
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) E(i, j) = i == j ? 0.0 : rng.uniform(0.0, 2.0);
        sel.set_task_error(E);
        for (const bool calibrated : {true, false})
          for (const bool lag_aware : {true, false})
            for (const Action& c : probe_candidates(0.5)) {
              SCOPED_TRACE(std::string(pool_name) + " sharpness " + std::to_string(sharp) + " updates " +
                           std::to_string(updates) + (calibrated ? " calibrated" : " reference") +
                           (lag_aware ? " lag-aware" : " lag-blind"));
              const Reference ref = reference(b, active, c, R, calibrated, lag_aware, E, &flushed, &deep);
              const double eh = sel.expected_entropy(b, c, R, calibrated, lag_aware);
              const Eigen::MatrixXd q = sel.last_posteriors();
              ASSERT_EQ(q.rows(), n);
              for (int h = 0; h < n; ++h)
                for (int j = 0; j < n; ++j)
                  ASSERT_LE(std::abs(q(j, h) - ref.q(j, h)), 1e-12 * ref.q(j, h) + 1e-300)
                      << "posterior " << j << " of column " << h << ": " << q(j, h) << " vs " << ref.q(j, h);
              EXPECT_TRUE(near(eh, ref.entropy)) << eh << " vs " << ref.entropy;
              const double ef = sel.expected_future_regret(b, c, R, calibrated, lag_aware);
              EXPECT_TRUE(near(ef, ref.regret)) << ef << " vs " << ref.regret;
              ++compared;
            }
      }
    }
  }
  EXPECT_EQ(compared, 2 * 3 * 3 * 4 * 12);
  // both sides of the cutoff occur: entries rounded to 0, and entries between −708 and −30 that
  // a cutoff moved up into that range would have dropped
  EXPECT_GT(flushed, 1000);
  EXPECT_GT(deep, 1000);
}

TEST(ProbeSelectorKernel, ActiveSetsOfEverySizeUpToTheLaneWidthAgree) {
  // n = 1 .. 9: the rows are padded to a multiple of four lanes; the padding must not leak
  const std::vector<Contract> pool = reference::pool9();
  const ResponseModel model = testing::pick_like();
  PoolBelief b(pool, model);
  Decoder env(pool[3]);
  const Action raw = testing::intent(2);
  b.update(raw, model.expected(env.step(raw)), Mat3::Identity());
  const Eigen::MatrixXd E9 = Eigen::MatrixXd::Constant(9, 9, 1.0) - Eigen::MatrixXd::Identity(9, 9);
  int flushed = 0, deep = 0;
  for (int n = 1; n <= 9; ++n) {
    std::vector<int> active(static_cast<std::size_t>(n));
    for (int j = 0; j < n; ++j) active[static_cast<std::size_t>(j)] = (2 * j + 1) % 9;
    std::sort(active.begin(), active.end());
    ProbeSelector sel(9, n, 4);
    sel.set_active(b, active);
    const Eigen::MatrixXd E = E9.topLeftCorner(n, n);
    sel.set_task_error(E);
    for (const Action& c : probe_candidates(0.5)) {
      const Reference ref = reference(b, active, c, Mat3::Identity(), true, true, E, &flushed, &deep);
      EXPECT_TRUE(near(sel.expected_entropy(b, c, Mat3::Identity(), true, true), ref.entropy)) << "n = " << n;
      EXPECT_TRUE(near(sel.expected_future_regret(b, c, Mat3::Identity(), true, true), ref.regret)) << "n = " << n;
    }
  }
}

}  // namespace
}  // namespace actionshift::adapt
