// Prints the bit patterns (hex floats) of the probe selector's results over a sweep of beliefs:
// every expected entropy, motion, posterior and expected regret of the 12 candidates under both
// previews, and every task-error matrix and current regret. Built twice (tests/adapt/CMakeLists.txt):
// against the library, whose kernels are cloned for AVX2 and baseline x86-64, and with the
// selector compiled for baseline x86-64 only; test `ProbeKernel.AvxAndBaselineGiveTheSameBits`
// requires the two outputs to be identical. usage: actionshift_probe_kernel_dump OUT_FILE
#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/probe_selector.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/data/builtin_manifests.hpp"

#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
  using namespace actionshift;
  using namespace actionshift::adapt;
  if (argc != 2) {
    std::fprintf(stderr, "usage: actionshift_probe_kernel_dump OUT_FILE\n");
    return 2;
  }
  std::FILE* out = std::fopen(argv[1], "w");
  if (!out) {
    std::fprintf(stderr, "actionshift: error: %s: cannot open for writing\n", argv[1]);
    return 2;
  }
#if defined(__x86_64__) && defined(__GNUC__)
  std::fprintf(stderr, "this CPU %s AVX2\n", __builtin_cpu_supports("avx2") ? "has" : "lacks");
#endif
  Rng rng(7);
  for (const char* pool_name : {"reference9", "full"}) {
    const std::vector<Contract> pool = data::resolve_manifest(pool_name).contracts();
    for (const double sharp : {1.0, 10.0, 50.0}) {
      ResponseModel m{{0.032, 0.016, 0.018, -0.035, -0.027, -0.038}, {0.03, 0.02, 0.02, 0.04, 0.05, 0.04}};
      for (auto& s : m.sigma) s /= sharp;
      for (const int updates : {0, 1, 3, 6}) {
        PoolBelief b(pool, m);
        Decoder env(pool[static_cast<std::size_t>(rng.uniform_int(pool.size()))]);
        for (int k = 0; k < updates; ++k) {
          Action a;
          for (int c = 0; c < kActionDim; ++c) a[c] = rng.uniform(-1, 1);
          Pose6 o = m.expected(env.step(a));
          for (int c = 0; c < kPoseDim; ++c) o[c] += m.sigma[static_cast<std::size_t>(c)] * rng.normal();
          b.update(a, o, Mat3::Identity());
        }
        ProbeSelector sel(b.size(), 32, 8);
        sel.select_active(b, 32, 1 - 1e-9);
        const int n = sel.num_active();
        std::vector<Action> recent(8);
        for (auto& a : recent)
          for (int c = 0; c < kActionDim; ++c) a[c] = rng.uniform(-1, 1);
        sel.compute_task_error(b, recent, Mat3::Identity());
        const Eigen::MatrixXd T = sel.task_error();
        for (Eigen::Index i = 0; i < T.size(); ++i) std::fprintf(out, "%a ", T.data()[i]);
        std::fprintf(out, "%a\n", sel.current_regret());
        Eigen::MatrixXd E(n, n);
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) E(i, j) = rng.uniform();
        sel.set_task_error(E);
        for (const bool calibrated : {true, false})
          for (const bool lag_aware : {true, false})
            for (const Action& c : probe_candidates(0.5)) {
              double motion = 0;
              std::fprintf(out, "%a ", sel.expected_entropy(b, c, Mat3::Identity(), calibrated, lag_aware, &motion));
              std::fprintf(out, "%a ", motion);
              const Eigen::MatrixXd q = sel.last_posteriors();
              for (Eigen::Index i = 0; i < q.size(); ++i) std::fprintf(out, "%a ", q.data()[i]);
              std::fprintf(out, "%a\n", sel.expected_future_regret(b, c, Mat3::Identity(), calibrated, lag_aware));
            }
      }
    }
  }
  return std::fclose(out) == 0 ? 0 : 1;
}
