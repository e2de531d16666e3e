// The project's one worker pool (core/workers.hpp): every worker index runs once, work pulled from a
// shared counter lands in per-item slots whatever the worker count, and a worker's exception reaches
// join().
#include "actionshift/core/workers.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace actionshift {
namespace {

std::vector<long> squares(unsigned threads, long n) {
  std::vector<long> out(static_cast<std::size_t>(n), -1);
  std::atomic<long> next{0};
  run_workers(threads, [&](unsigned) {
    for (long k = next++; k < n; k = next++) out[static_cast<std::size_t>(k)] = k * k;
  });
  return out;
}

TEST(WorkerPool, EveryWorkerRunsOnceAndResultsDoNotDependOnTheWorkerCount) {
  std::vector<std::atomic<int>> seen(5);
  run_workers(5, [&](unsigned w) { ++seen[w]; });
  for (auto& s : seen) EXPECT_EQ(s.load(), 1);
  EXPECT_EQ(squares(1, 1000), squares(2, 1000));
  EXPECT_EQ(squares(7, 1000), squares(1, 1000));
  EXPECT_EQ(squares(3, 1000)[999], 999L * 999L);
  EXPECT_EQ(WorkerPool(0, [](unsigned) {}).size(), 1u);  // at least one worker
  EXPECT_EQ(resolve_threads(3), 3u);
  EXPECT_GE(resolve_threads(0), 1u);
}

TEST(WorkerPool, TheFirstExceptionReachesJoinAfterEveryWorkerFinished) {
  std::atomic<int> finished{0};
  WorkerPool pool(4, [&](unsigned w) {
    ++finished;
    if (w == 2) throw std::runtime_error("worker 2 failed");
  });
  EXPECT_THROW(
      {
        try {
          pool.join();
        } catch (const std::runtime_error& e) {
          EXPECT_STREQ(e.what(), "worker 2 failed");
          throw;
        }
      },
      std::runtime_error);
  EXPECT_EQ(finished.load(), 4);
}

}  // namespace
}  // namespace actionshift
