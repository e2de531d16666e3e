// A probe selection and a batched belief update allocate nothing: every buffer is sized when the
// adapter or belief is built. malloc and calloc are interposed in this test executable (glibc:
// the real ones are __libc_*) to count every heap allocation, operator new's and Eigen's alike,
// inside a window.
#include "actionshift/adapt/batched_belief.hpp"
#include "actionshift/adapt/methods.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>

extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void note() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" void* malloc(std::size_t n) {
  note();
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t n, std::size_t s) {
  note();
  return __libc_calloc(n, s);
}
extern "C" void* realloc(void* p, std::size_t n) {
  note();
  return __libc_realloc(p, n);
}

namespace actionshift::adapt {
namespace {

struct Counting {
  Counting() {
    g_allocations = 0;
    g_counting = true;
  }
  ~Counting() { g_counting = false; }
  long count() const { return g_allocations.load(); }
};

template <class A>
long allocations_over_an_episode(A& a, const Contract& truth, int& probes) {
  Decoder env(truth);
  Rng rng(3);
  a.begin_episode(3);
  const Mat3 R = Mat3::Identity();
  std::vector<Pose6> noise(12);
  for (auto& n : noise)
    for (int c = 0; c < kPoseDim; ++c) n[c] = 0.01 * rng.normal();
  Counting window;
  for (int k = 0; k < 12; ++k) {
    const Action raw = a.encode(testing::intent(k), R);
    probes += a.last_step().probe ? 1 : 0;
    a.observe(raw, testing::pick_like().expected(env.step(raw, R)) + noise[static_cast<std::size_t>(k)], R);
  }
  return window.count();
}

TEST(Allocation, EntropyAndDualAbiEpisodesAllocateNothing) {
  for (const char* pool_name : {"reference9", "full"}) {
    const auto pool = data::resolve_manifest(pool_name).contracts();
    ProbeOptions o;
    o.budget = 12;
    ProbingAdapter entropy(pool, testing::pick_like(), ProbeStrategy::kEntropy, o);
    DualAbiAdapter dual(pool, testing::pick_like(), 0.0, o);
    int probes = 0;
    EXPECT_EQ(allocations_over_an_episode(entropy, pool[3], probes), 0) << pool_name;
    EXPECT_EQ(probes, 12);
    probes = 0;
    EXPECT_EQ(allocations_over_an_episode(dual, pool[3], probes), 0) << pool_name;
    EXPECT_GT(probes, 0);
  }
}

TEST(Allocation, BatchedBeliefUpdateAllocatesNothing) {
  BatchedPoolBelief b(reference::pool9(), testing::pick_like(), 16);
  const BatchedPoolBelief::Batch raw = BatchedPoolBelief::Batch::Constant(kActionDim, 16, 0.3);
  const BatchedPoolBelief::PoseBatch obs = BatchedPoolBelief::PoseBatch::Constant(kPoseDim, 16, 0.01);
  Counting window;
  for (int k = 0; k < 5; ++k) b.update(raw, obs);
  EXPECT_EQ(window.count(), 0);
  // the counter works: an allocation inside the window is seen
  auto* v = new std::vector<int>(3);
  EXPECT_GE(window.count(), 1);
  delete v;
}

}  // namespace
}  // namespace actionshift::adapt
