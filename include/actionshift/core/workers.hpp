#pragma once
/// \file The project's one worker pool: every parallel loop (the evaluation runner, policy rollouts,
/// DAgger data collection, the environment bench) runs its workers through WorkerPool, so thread
/// counts, joining and error propagation behave the same everywhere.
///
/// A pool starts `size` threads that each run `body(worker_index)` once (a body typically pulls work
/// items from a shared atomic counter); join() waits for all of them and rethrows the first
/// exception a body let escape. Results must not depend on the number of workers: callers write
/// per-item results into slots indexed by the item, never by the worker.

#include <algorithm>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace actionshift {

/// `requested` threads, or the hardware concurrency (at least 1) for 0.
inline unsigned resolve_threads(unsigned requested) {
  return requested > 0 ? requested : std::max(1u, std::thread::hardware_concurrency());
}

class WorkerPool {
 public:
  /// Starts max(1, threads) workers running body(0) … body(threads − 1).
  WorkerPool(unsigned threads, std::function<void(unsigned)> body) : body_(std::move(body)) {
    const unsigned n = std::max(1u, threads);
    threads_.reserve(n);
    for (unsigned w = 0; w < n; ++w)
      threads_.emplace_back([this, w] {
        try {
          body_(w);
        } catch (...) {
          std::lock_guard<std::mutex> lock(mu_);
          if (!error_) error_ = std::current_exception();
        }
      });
  }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  /// Joins (never throws; call join() to see a worker's exception).
  ~WorkerPool() {
    for (auto& t : threads_)
      if (t.joinable()) t.join();
  }

  unsigned size() const noexcept { return static_cast<unsigned>(threads_.size()); }

  /// Waits for every worker; rethrows the first exception one of them threw.
  void join() {
    for (auto& t : threads_)
      if (t.joinable()) t.join();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::function<void(unsigned)> body_;
  std::vector<std::thread> threads_;
  std::mutex mu_;
  std::exception_ptr error_;
};

/// Runs body(0..threads−1) on a WorkerPool and waits; rethrows the first exception.
inline void run_workers(unsigned threads, const std::function<void(unsigned)>& body) {
  WorkerPool pool(threads, body);
  pool.join();
}

}  // namespace actionshift
