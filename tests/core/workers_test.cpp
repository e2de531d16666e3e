// The project's one worker pool (core/workers.hpp): every worker index runs once per round, work pulled
// from a shared counter lands in per-item slots whatever the worker count, a worker's exception reaches
// join(), and a pool runs many rounds on the same threads.
#include "actionshift/core/workers.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <thread>
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

TEST(WorkerPool, RoundsRunOnTheSameThreadsAndEachRoundsErrorIsItsOwn) {
  WorkerPool pool(3);
  EXPECT_EQ(pool.size(), 3u);
  std::mutex mu;
  std::set<std::thread::id> ids;
  std::vector<int> counts(3, 0);
  for (int round = 0; round < 200; ++round)
    pool.run([&](unsigned w) {
      std::lock_guard<std::mutex> lock(mu);
      ids.insert(std::this_thread::get_id());
      ++counts[w];
    });
  EXPECT_EQ(ids.size(), 3u);  // no thread started per round
  EXPECT_EQ(counts, std::vector<int>({200, 200, 200}));
  EXPECT_EQ(ids.count(std::this_thread::get_id()), 0u);
  // a failing round throws from its join; the next round starts clean
  EXPECT_THROW(pool.run([](unsigned w) {
    if (w == 1) throw std::runtime_error("round failed");
  }), std::runtime_error);
  std::atomic<int> ran{0};
  EXPECT_NO_THROW(pool.run([&](unsigned) { ++ran; }));
  EXPECT_EQ(ran.load(), 3);
  // start() returns at once; a second start() waits for the first round; the destructor waits too
  std::atomic<int> slow{0};
  {
    WorkerPool p(2);
    p.start([&](unsigned) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      ++slow;
    });
    p.start([&](unsigned) { ++slow; });
    EXPECT_GE(slow.load(), 2);
  }
  EXPECT_EQ(slow.load(), 4);
}

}  // namespace
}  // namespace actionshift
