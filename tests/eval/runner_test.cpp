#include "actionshift/eval/runner.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/eval/store.hpp"
#include "fake_episode.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

namespace actionshift::eval {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

class RunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("actionshift_runner_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
             std::to_string(::getpid()));
    fs::remove_all(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  RunOptions opts(const std::string& sub, unsigned threads) {
    RunOptions o;
    o.out_dir = (root_ / sub).string();
    o.threads = threads;
    o.progress = ProgressMode::off;
    return o;
  }
  fs::path root_;
};

TEST_F(RunnerTest, OutputIsByteIdenticalForOneAndTwoThreads) {
  const JobSpec job = testing::fake_job(97);
  const auto a = run_job(job, testing::fake_episode_fn(), opts("one", 1));
  // jitter makes the two workers finish out of order
  auto jittery = [base = testing::fake_episode_fn()](const EpisodeTask& t) {
    std::this_thread::sleep_for(std::chrono::microseconds((t.episode_seed % 5) * 200));
    return base(t);
  };
  const auto b = run_job(job, jittery, opts("two", 2));
  const auto c = run_job(job, testing::fake_episode_fn(), opts("four", 4));
  EXPECT_EQ(a.episodes_run, 97);
  EXPECT_EQ(b.episodes_run, 97);
  const std::string ref = slurp(a.jsonl_path);
  EXPECT_EQ(std::count(ref.begin(), ref.end(), '\n'), 97);
  EXPECT_EQ(slurp(b.jsonl_path), ref);
  EXPECT_EQ(slurp(c.jsonl_path), ref);
  EXPECT_EQ(fs::path(a.jsonl_path).filename().string(), job_id(job) + ".jsonl");
}

TEST_F(RunnerTest, StampsJobFieldsAndDealsEpisodesOverContracts) {
  const JobSpec job = testing::fake_job(10);
  std::mutex mu;
  std::set<std::int64_t> seen;
  std::map<std::int64_t, std::set<std::uint64_t>> adapter_seeds;  // by index within the contract
  auto fn = [&](const EpisodeTask& t) {
    EXPECT_EQ(t.job, &job);
    EXPECT_EQ(t.contract_index, episode_slot(job.seed, 3, t.episode_index).contract_index);
    EXPECT_EQ(t.contract_episode, t.episode_index / 3);
    EXPECT_EQ(t.episode_seed, episode_seed(job.seed, t.contract_episode));
    EXPECT_EQ(t.adapter_seed, adapter_episode_seed(job.seed, t.contract_episode));
    std::lock_guard lock(mu);
    seen.insert(t.episode_index);
    adapter_seeds[t.contract_episode].insert(t.adapter_seed);
    return testing::fake_episode_fn()(t);
  };
  const auto r = run_job(job, fn, opts("x", 2));
  EXPECT_EQ(seen.size(), 10u);
  // the adapter's seed is the same for every contract: the k-th episode of contracts 0, 1 and 2
  // get one seed, so it tells an adapter nothing about which contract it faces
  ASSERT_EQ(adapter_seeds.size(), 4u);  // 10 episodes over 3 contracts: within-contract indices 0..3
  for (const auto& [k, seeds] : adapter_seeds) EXPECT_EQ(seeds.size(), 1u) << "contract episode " << k;
  EXPECT_NE(*adapter_seeds[0].begin(), *adapter_seeds[1].begin());
  const auto file = read_record_file(r.jsonl_path);
  ASSERT_EQ(file.records.size(), 10u);
  for (std::size_t i = 0; i < 10; ++i) {
    const auto& rec = file.records[i];
    EXPECT_EQ(rec.episode_index, static_cast<std::int64_t>(i));
    EXPECT_EQ(rec.contract_index, episode_slot(job.seed, 3, static_cast<std::int64_t>(i)).contract_index);
    EXPECT_EQ(rec.job_id, job_id(job));
    EXPECT_EQ(rec.method, "oracle");
    EXPECT_EQ(rec.backbone_sha256, job.backbone.sha256);
  }
  const auto summary = nlohmann::json::parse(slurp(r.summary_path));
  EXPECT_EQ(summary["complete"], true);
  EXPECT_EQ(summary["episodes_done"], 10);
  EXPECT_THAT(summary["message"].get<std::string>(), HasSubstr("complete"));
}

TEST_F(RunnerTest, FinishedJobIsANoOp) {
  const JobSpec job = testing::fake_job(12);
  const auto first = run_job(job, testing::fake_episode_fn(), opts("x", 2));
  const std::string bytes = slurp(first.jsonl_path);
  const auto mtime = fs::last_write_time(first.summary_path);
  int calls = 0;
  const auto again = run_job(job, [&](const EpisodeTask& t) { ++calls; return testing::fake_episode_fn()(t); }, opts("x", 2));
  EXPECT_TRUE(again.already_complete);
  EXPECT_EQ(again.episodes_run, 0);
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(slurp(first.jsonl_path), bytes);
  EXPECT_EQ(fs::last_write_time(first.summary_path), mtime);
  // a summary lost after the last record is restored
  fs::remove(first.summary_path);
  run_job(job, testing::fake_episode_fn(), opts("x", 2));
  EXPECT_TRUE(fs::exists(first.summary_path));
}

TEST_F(RunnerTest, FailingEpisodeKeepsEarlierRecordsAndResumes) {
  const JobSpec job = testing::fake_job(30);
  auto failing = [](const EpisodeTask& t) -> EpisodeRecord {
    if (t.episode_index == 17) throw std::runtime_error("simulator exploded");
    return testing::fake_episode_fn()(t);
  };
  EXPECT_THROW(run_job(job, failing, opts("x", 2)), std::runtime_error);
  const auto path = root_ / "x" / (job_id(job) + ".jsonl");
  EXPECT_EQ(read_record_file(path.string()).records.size(), 17u);
  const auto summary = nlohmann::json::parse(slurp(root_ / "x" / (job_id(job) + ".summary.json")));
  EXPECT_THAT(summary["message"].get<std::string>(), HasSubstr("stopped at episode 17 of 30 (simulator exploded); re-run to resume"));
  const auto r = run_job(job, testing::fake_episode_fn(), opts("x", 2));
  EXPECT_EQ(r.episodes_before, 17);
  EXPECT_EQ(r.episodes_run, 13);
  const auto ref = run_job(job, testing::fake_episode_fn(), opts("ref", 1));
  EXPECT_EQ(slurp(path), slurp(ref.jsonl_path));
}

TEST_F(RunnerTest, InterruptedJobKeepsItsFinishedEpisodesAndResumes) {
  const JobSpec job = testing::fake_job(200);
  // episodes of 2 ms; the hook says stop once 20 episodes have been run
  std::atomic<int> ran{0};
  auto slow = [&ran, base = testing::fake_episode_fn()](const EpisodeTask& t) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ++ran;
    return base(t);
  };
  std::atomic<int> polls{0};
  RunOptions o = opts("x", 2);
  o.interrupted = [&] {
    ++polls;
    return ran.load() >= 20;
  };
  EXPECT_THROW(run_job(job, slow, o), Interrupted);
  EXPECT_GT(polls.load(), 0);
  const auto path = root_ / "x" / (job_id(job) + ".jsonl");
  const std::size_t kept = read_record_file(path.string()).records.size();
  EXPECT_GE(kept, 1u);
  EXPECT_LT(kept, 200u);  // stopped early: 200 episodes take at least 200 ms on 2 workers, a poll comes every 100 ms
  const auto summary = nlohmann::json::parse(slurp(root_ / "x" / (job_id(job) + ".summary.json")));
  EXPECT_EQ(summary["message"].get<std::string>(),
            "interrupted after " + std::to_string(kept) + " of 200 episodes; re-run to resume");
  // resuming runs only the rest, and the file equals an uninterrupted run; a hook that never stops
  // the job changes nothing
  RunOptions again = opts("x", 2);
  again.interrupted = [] { return false; };
  const auto r = run_job(job, slow, again);
  EXPECT_EQ(r.episodes_before, static_cast<std::int64_t>(kept));
  EXPECT_EQ(r.episodes_run, 200 - static_cast<std::int64_t>(kept));
  const auto ref = run_job(job, testing::fake_episode_fn(), opts("ref", 1));
  EXPECT_EQ(slurp(path), slurp(ref.jsonl_path));
}

// a full disk (here: a file-size limit) fails the JSONL append first; the summary written afterwards
// fails too, and its error must not hide the first one
TEST_F(RunnerTest, FirstIoErrorIsTheOneReported) {
  const JobSpec job = testing::fake_job(40);
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(fds[0]);
    ::signal(SIGXFSZ, SIG_IGN);  // writes past the limit fail with EFBIG instead of killing the process
    const rlimit limit{600, 600};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    std::string message = "no error";
    try {
      run_job(job, testing::fake_episode_fn(), opts("full", 1));
    } catch (const std::exception& e) {
      message = e.what();
    }
    const ssize_t n = ::write(fds[1], message.data(), message.size());
    ::_exit(n > 0 ? 0 : 1);
  }
  ::close(fds[1]);
  std::string message;
  char buf[512];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) message.append(buf, static_cast<std::size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_THAT(message, HasSubstr(job_id(job) + ".jsonl: write failed"));
  EXPECT_THAT(message, ::testing::Not(HasSubstr("summary")));
}

TEST_F(RunnerTest, InvalidRecordFromEpisodeFunctionStopsTheJob) {
  const JobSpec job = testing::fake_job(5);
  auto bad = [](const EpisodeTask& t) {
    EpisodeRecord r = testing::fake_episode_fn()(t);
    if (t.episode_index == 2) r.task_return = std::nan("");
    return r;
  };
  EXPECT_THAT([&] { run_job(job, bad, opts("x", 1)); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("episode 2: return: must be finite")));
}

TEST_F(RunnerTest, ResumesAfterTornLineByteIdentically) {
  const JobSpec job = testing::fake_job(40);
  const auto ref = run_job(job, testing::fake_episode_fn(), opts("ref", 2));
  const std::string want = slurp(ref.jsonl_path);
  // an interrupted run: the first 23 lines and half of the 24th
  fs::create_directories(root_ / "x");
  const auto path = root_ / "x" / (job_id(job) + ".jsonl");
  std::size_t cut = 0;
  for (int i = 0; i < 23; ++i) cut = want.find('\n', cut) + 1;
  {
    std::ofstream f(path, std::ios::binary);
    f << want.substr(0, cut + 40);
  }
  std::ostringstream log;
  auto o = opts("x", 2);
  o.log = &log;
  const auto r = run_job(job, testing::fake_episode_fn(), o);
  EXPECT_EQ(r.episodes_before, 23);
  EXPECT_THAT(log.str(), HasSubstr("repaired a torn last line"));
  EXPECT_EQ(slurp(path), want);
}

TEST_F(RunnerTest, ProgressLinesReportRateAndCompletion) {
  const JobSpec job = testing::fake_job(8);
  std::ostringstream log;
  auto o = opts("x", 2);
  o.progress = ProgressMode::lines;
  o.log = &log;
  run_job(job, testing::fake_episode_fn(), o);
  EXPECT_THAT(log.str(), HasSubstr("8/8 episodes"));
  EXPECT_THAT(log.str(), HasSubstr("episodes/s"));
  EXPECT_THAT(log.str(), HasSubstr("done in"));
  EXPECT_EQ(log.str().find('\r'), std::string::npos);
  std::ostringstream bar;
  o.out_dir = (root_ / "y").string();
  o.progress = ProgressMode::bar;
  o.log = &bar;
  run_job(job, testing::fake_episode_fn(), o);
  EXPECT_THAT(bar.str(), HasSubstr("\r"));
  EXPECT_THAT(bar.str(), HasSubstr("[########################]"));
}

// the helper executable runs the same fake job; it is killed with SIGKILL mid-run, then resumed
pid_t spawn_helper(const fs::path& out, int episodes, int threads, int sleep_ms) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string e = std::to_string(episodes), t = std::to_string(threads), s = std::to_string(sleep_ms);
    ::execl(ACTIONSHIFT_EVAL_FAKE_JOB, ACTIONSHIFT_EVAL_FAKE_JOB, out.c_str(), e.c_str(), t.c_str(), s.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int wait_status(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

std::size_t line_count(const fs::path& p) {
  const std::string s = slurp(p);
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

TEST_F(RunnerTest, SigkillThenResumeGivesByteIdenticalOutput) {
  constexpr int kEpisodes = 80;
  const JobSpec job = testing::fake_job(kEpisodes);
  const std::string name = job_id(job) + ".jsonl";
  // uninterrupted reference through the same executable
  ASSERT_EQ(WEXITSTATUS(wait_status(spawn_helper(root_ / "ref", kEpisodes, 2, 0))), 0);
  const std::string want = slurp(root_ / "ref" / name);
  ASSERT_EQ(std::count(want.begin(), want.end(), '\n'), kEpisodes);

  const fs::path out = root_ / "killed";
  std::size_t previous = 0;
  for (std::size_t kill_after : {8u, 30u}) {  // two kills at different points
    const pid_t pid = spawn_helper(out, kEpisodes, 2, 15);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (line_count(out / name) < kill_after && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ::kill(pid, SIGKILL);
    const int status = wait_status(pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "helper finished before it could be killed";
    const std::size_t have = line_count(out / name);
    EXPECT_GE(have, kill_after);
    EXPECT_LT(have, static_cast<std::size_t>(kEpisodes));
    EXPECT_GE(have, previous);
    previous = have;
    // what is there is a valid prefix of the reference
    const std::string part = slurp(out / name);
    EXPECT_EQ(want.compare(0, part.size(), part), 0);
  }
  ASSERT_EQ(WEXITSTATUS(wait_status(spawn_helper(out, kEpisodes, 2, 0))), 0);
  EXPECT_EQ(slurp(out / name), want);
  const auto summary = nlohmann::json::parse(slurp(out / (job_id(job) + ".summary.json")));
  EXPECT_EQ(summary["complete"], true);
  EXPECT_THAT(summary["message"].get<std::string>(), HasSubstr("resumed"));
}

}  // namespace
}  // namespace actionshift::eval
