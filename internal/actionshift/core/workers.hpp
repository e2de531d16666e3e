#pragma once
/// \file The project's one worker pool: every parallel loop (the evaluation runner, policy rollouts,
/// DAgger data collection, the vectorised environment sim::VecEnv of PPO and the Python module's
/// make_vec, the environment bench) runs its workers through WorkerPool, so thread counts, joining and
/// error propagation behave the same everywhere.
///
/// A pool keeps `size` threads for its lifetime; each round (start/join, or run) has every worker run
/// `body(worker_index)` once (a body typically pulls work items from a shared atomic counter), and
/// join() waits for all of them and rethrows the first exception a body let escape. A loop that runs
/// many rounds (PPO's environment steps and gradient chunks, the Python VecEnv's steps) keeps one pool
/// instead of starting threads per round. Results must not depend on the number of workers: callers
/// write per-item results into slots indexed by the item, never by the worker.

#include <algorithm>
#include <condition_variable>
#include <cstdint>
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
  /// Starts max(1, threads) worker threads, idle until start() or run() gives them a round.
  explicit WorkerPool(unsigned threads) {
    const unsigned n = std::max(1u, threads);
    threads_.reserve(n);
    for (unsigned w = 0; w < n; ++w) threads_.emplace_back([this, w] { loop(w); });
  }
  /// Starts max(1, threads) workers and a first round running body(0) … body(threads − 1).
  WorkerPool(unsigned threads, std::function<void(unsigned)> body) : WorkerPool(threads) { start(std::move(body)); }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  /// Waits for a running round and stops the threads (never throws; call join() to see a worker's exception).
  ~WorkerPool() {
    {
      std::unique_lock<std::mutex> lock(mu_);
      idle_.wait(lock, [this] { return pending_ == 0; });
      stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
  }

  unsigned size() const noexcept { return static_cast<unsigned>(threads_.size()); }

  /// Starts a round: every worker w runs body(w) once; returns at once (one round at a time: a second
  /// start() first waits for the running round to finish).
  void start(std::function<void(unsigned)> body) {
    {
      std::unique_lock<std::mutex> lock(mu_);
      idle_.wait(lock, [this] { return pending_ == 0; });
      body_ = std::move(body);
      pending_ = size();
      error_ = nullptr;
      ++generation_;
    }
    wake_.notify_all();
  }

  /// Waits for the round to finish; rethrows the first exception one of its bodies threw.
  void join() {
    std::unique_lock<std::mutex> lock(mu_);
    idle_.wait(lock, [this] { return pending_ == 0; });
    if (error_) {
      std::exception_ptr e = error_;
      error_ = nullptr;
      std::rethrow_exception(e);
    }
  }

  /// start(body) then join(): the persistent pool's parallel loop (no thread is started per call).
  void run(std::function<void(unsigned)> body) {
    start(std::move(body));
    join();
  }

 private:
  void loop(unsigned w) {
    std::uint64_t seen = 0;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mu_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
      }
      std::exception_ptr err;
      try {
        body_(w);  // body_ is not reassigned before every worker of this round has finished
      } catch (...) {
        err = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mu_);
      if (err && !error_) error_ = err;
      if (--pending_ == 0) idle_.notify_all();
    }
  }

  std::vector<std::thread> threads_;
  std::function<void(unsigned)> body_;
  std::mutex mu_;
  std::condition_variable wake_, idle_;
  unsigned pending_{0};
  std::uint64_t generation_{0};
  bool stop_{false};
  std::exception_ptr error_;
};

/// Runs body(0..threads−1) on a WorkerPool and waits; rethrows the first exception.
inline void run_workers(unsigned threads, const std::function<void(unsigned)>& body) {
  WorkerPool pool(threads, body);
  pool.join();
}

}  // namespace actionshift
