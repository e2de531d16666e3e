#include "actionshift/eval/runner.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/workers.hpp"
#include "actionshift/eval/provenance.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/eval/store.hpp"
#include "io.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

namespace actionshift::eval {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// progress display: a self-overwriting bar on a terminal, periodic log lines otherwise
class Progress {
 public:
  Progress(ProgressMode mode, std::ostream& out, std::string id, std::int64_t before, std::int64_t total)
      : out_(out), id_(std::move(id)), before_(before), total_(total), t0_(Clock::now()), last_(t0_) {
    if (mode == ProgressMode::automatic) mode = ::isatty(STDERR_FILENO) ? ProgressMode::bar : ProgressMode::lines;
    mode_ = mode;
  }

  void update(std::int64_t done) {
    if (mode_ == ProgressMode::off) return;
    const auto now = Clock::now();
    const double since_last = std::chrono::duration<double>(now - last_).count();
    if (since_last < (mode_ == ProgressMode::bar ? 0.1 : 5.0)) return;
    last_ = now;
    show(done, false);
  }

  void finish(std::int64_t done) {
    if (mode_ == ProgressMode::off) return;
    show(done, true);
  }

  // ends the bar's unfinished line, if one is on the screen, before a message is written after it
  // (a newline written without a bar made the first line of a full disk's error report blank)
  void break_line() {
    if (!open_line_) return;
    out_ << "\n";
    open_line_ = false;
  }

 private:
  void show(std::int64_t done, bool final) {
    const double elapsed = seconds_since(t0_);
    const double rate = elapsed > 0.0 ? static_cast<double>(done - before_) / elapsed : 0.0;
    const double eta = rate > 0.0 ? static_cast<double>(total_ - done) / rate : -1.0;
    char head[160];
    std::snprintf(head, sizeof head, "%lld/%lld episodes  %.1f episodes/s  ", static_cast<long long>(done),
                  static_cast<long long>(total_), rate);
    const std::string short_id = id_.substr(0, 12);
    if (mode_ == ProgressMode::bar) {
      constexpr int kWidth = 24;
      const int filled = total_ > 0 ? static_cast<int>(kWidth * done / total_) : kWidth;
      std::string bar(static_cast<std::size_t>(filled), '#');
      bar.resize(kWidth, '.');
      out_ << "\r" << short_id << " [" << bar << "] " << head
           << (final ? "done in " + detail::format_seconds(elapsed) : "ETA " + detail::format_seconds(eta)) << "   ";
      if (final) out_ << "\n";
      open_line_ = !final;
      out_.flush();
    } else {
      out_ << "actionshift: job " << short_id << ": " << head
           << (final ? "done in " + detail::format_seconds(elapsed) : "ETA " + detail::format_seconds(eta)) << "\n";
      out_.flush();
    }
  }

  std::ostream& out_;
  ProgressMode mode_{ProgressMode::off};
  bool open_line_{false};  // the bar's line has no newline yet
  std::string id_;
  std::int64_t before_, total_;
  Clock::time_point t0_, last_;
};

}  // namespace

EpisodeTask episode_task(const JobSpec& job, std::int64_t episode_index, unsigned worker) {
  if (episode_index < 0 || episode_index >= job.episodes)
    throw std::invalid_argument("episode " + std::to_string(episode_index) + " is outside the job's " +
                                std::to_string(job.episodes) + " episodes");
  const auto slot = episode_slot(job.seed, job.split.contracts, episode_index);
  return EpisodeTask{&job,
                     job.seed,
                     slot.contract_index,
                     slot.contract_episode,
                     episode_index,
                     episode_seed(job.seed, slot.contract_episode),
                     adapter_episode_seed(job.seed, slot.contract_episode),
                     worker};
}

void stamp_record(EpisodeRecord& r, const JobSpec& job, const std::string& job_id, const EpisodeTask& task) {
  r.schema_version = std::string(kRecordSchemaVersion);
  r.job_id = job_id;
  r.task = job.task;
  r.split = job.split.name;
  r.method = job.method;
  r.method_variant = method_variant(job);
  r.seed = job.seed;
  r.contract_index = task.contract_index;
  r.episode_index = task.episode_index;
  r.backbone = job.backbone.name;
  r.backbone_sha256 = job.backbone.sha256;
  r.profile = job.profile;
  r.obs_noise = job.obs_noise;
  r.actionshift_version = build_provenance().version;
  r.git_commit = build_provenance().git_commit;
}

RunResult run_job(const JobSpec& job, const EpisodeFn& fn, const RunOptions& options) {
  const auto t0 = Clock::now();
  std::ostream& log = options.log ? *options.log : std::cerr;
  ResultStore store = ResultStore::open(options.out_dir, job, StoreOptions{options.fsync, &log});

  RunResult result;
  result.job_id = store.job_id();
  result.jsonl_path = store.jsonl_path();
  result.summary_path = store.summary_path();
  result.episodes_total = job.episodes;
  result.episodes_before = store.episodes_done();

  // a finished job is a no-op (its summary, when it has one, matched its records when the store was
  // opened); only a summary that is missing (killed before writing it), covers fewer records, or has no
  // records hash (schema 1.0) is written again
  if (store.complete()) {
    result.already_complete = true;
    if (!store.summarized() || *store.summarized() < store.episodes_done())
      write_json_atomic(store.summary_path(),
                        make_job_summary(job, store.records(), 0, seconds_since(t0),
                                         "complete: " + std::to_string(job.episodes) + " episodes (summary restored)",
                                         store.records_sha256()));
    result.wall_time_s = seconds_since(t0);
    return result;
  }

  unsigned threads = resolve_threads(options.threads);
  const std::int64_t first = store.episodes_done();
  const std::int64_t remaining = job.episodes - first;
  threads = static_cast<unsigned>(std::min<std::int64_t>(threads, remaining));
  // workers may run at most `window` episodes ahead of the writer (bounds the reorder buffer)
  const std::int64_t window = std::max<std::int64_t>(64, 8 * static_cast<std::int64_t>(threads));

  std::mutex mu;
  std::condition_variable cv;
  std::map<std::int64_t, EpisodeRecord> ready;  // reorder buffer: finished, not yet written
  std::int64_t written = first;                 // next index to write (guarded by mu)
  std::int64_t failed_at = -1;                  // lowest failing episode (guarded by mu)
  std::exception_ptr failure;
  std::atomic<std::int64_t> next{first};

  auto worker = [&](unsigned w) {
    for (;;) {
      const std::int64_t i = next.fetch_add(1);
      if (i >= job.episodes) return;
      {
        std::unique_lock lock(mu);
        cv.wait(lock, [&] { return i < written + window || failure; });
        if (failure && i > failed_at) return;
      }
      const EpisodeTask task = episode_task(job, i, w);
      try {
        EpisodeRecord r = fn(task);
        // stamp the job fields; the episode function owns only the outcome and contract hash
        stamp_record(r, job, store.job_id(), task);
        validate_record(r, "episode " + std::to_string(i));
        std::lock_guard lock(mu);
        ready.emplace(i, std::move(r));
      } catch (...) {
        std::lock_guard lock(mu);
        if (!failure || i < failed_at) {
          failure = std::current_exception();
          failed_at = i;
        }
      }
      cv.notify_all();
    }
  };

  WorkerPool pool(threads, worker);

  Progress progress(options.progress, log, store.job_id(), first, job.episodes);
  std::exception_ptr write_failure;
  bool was_interrupted = false;
  {
    std::unique_lock lock(mu);
    const auto next_or_failed = [&] { return ready.count(written) || (failure && written >= failed_at); };
    // options.interrupted, at most every 100 ms (episodes may finish faster than that); the lock is
    // held on entry and exit but not during the call
    auto last_poll = Clock::now();
    const auto poll_interrupted = [&] {
      if (Clock::now() - last_poll < std::chrono::milliseconds(100)) return;
      last_poll = Clock::now();
      lock.unlock();
      const bool stop = options.interrupted();
      lock.lock();
      if (stop && (!failure || written < failed_at)) {
        // stops the workers like a failing episode; what is thrown is said after the last write
        failure = std::make_exception_ptr(Interrupted("interrupted"));
        failed_at = written;
        was_interrupted = true;
        cv.notify_all();
      }
    };
    while (written < job.episodes) {
      if (!options.interrupted) {
        cv.wait(lock, next_or_failed);
      } else {
        while (!cv.wait_for(lock, std::chrono::milliseconds(100), next_or_failed)) poll_interrupted();
        poll_interrupted();
      }
      if (!ready.count(written)) {  // the next episode failed: stop at the last contiguous record
        // an episode that failed because of the interrupt (an external policy stops waiting for its
        // reply at SIGINT/SIGTERM) stops the job as the interrupt, not as an error
        if (failure && !was_interrupted && options.interrupted) {
          lock.unlock();
          const bool stop = options.interrupted();
          lock.lock();
          if (stop) {
            failure = std::make_exception_ptr(Interrupted("interrupted"));
            was_interrupted = true;
          }
        }
        break;
      }
      EpisodeRecord r = std::move(ready.at(written));
      ready.erase(written);
      lock.unlock();
      try {
        store.append(r);
      } catch (...) {
        write_failure = std::current_exception();
      }
      lock.lock();
      if (write_failure) {
        if (!failure || written < failed_at) {
          failure = write_failure;
          failed_at = written;
        }
        cv.notify_all();
        break;
      }
      ++written;
      cv.notify_all();
      lock.unlock();
      progress.update(store.episodes_done());
      lock.lock();
    }
  }
  pool.join();  // workers keep their own exceptions (failure); join() never sees one

  result.episodes_run = store.episodes_done() - first;
  result.wall_time_s = seconds_since(t0);
  std::string message;
  // the count of the summary: episodes that finished after the signal are written too
  const std::string interrupted_after =
      "interrupted after " + std::to_string(store.episodes_done()) + " of " + std::to_string(job.episodes) + " episodes";
  if (failure && was_interrupted) {
    message = interrupted_after + "; re-run to resume";
  } else if (failure) {
    // the reason is kept with the job, so a summary read later says why it stopped
    std::string why = "unknown error";
    try {
      std::rethrow_exception(failure);
    } catch (const std::exception& e) {
      why = printable_input(e.what(), 500);
    } catch (...) {
    }
    message = "stopped at episode " + std::to_string(failed_at) + " of " + std::to_string(job.episodes) + " (" + why +
              "); re-run to resume";
  } else {
    message = "complete: " + std::to_string(job.episodes) + " episodes" +
              (first > 0 ? " (resumed after " + std::to_string(first) + ")" : "");
  }
  if (failure) {
    // the first error is the one reported: on a full disk the summary cannot be written either,
    // and its error would hide the JSONL append that failed first
    try {
      write_json_atomic(store.summary_path(), make_job_summary(job, store.records(), result.episodes_run, result.wall_time_s,
                                                               message, store.records_sha256()));
    } catch (const std::exception& e) {
      progress.break_line();
      log << "actionshift: note: job summary not written either (" << printable_input(e.what(), 500) << ")\n";
    }
    progress.break_line();
    if (was_interrupted) throw Interrupted(interrupted_after);
    std::rethrow_exception(failure);
  }
  write_json_atomic(store.summary_path(),
                    make_job_summary(job, store.records(), result.episodes_run, result.wall_time_s, message, store.records_sha256()));
  progress.finish(store.episodes_done());
  return result;
}

}  // namespace actionshift::eval
