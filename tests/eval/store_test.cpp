#include "actionshift/eval/store.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/eval/statistics.hpp"
#include "fake_episode.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace actionshift::eval {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

std::string slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("actionshift_store_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // record i of `job` as the runner would stamp it
  static EpisodeRecord record(const JobSpec& job, std::int64_t i) {
    const auto slot = episode_slot(job.seed, job.split.contracts, i);
    EpisodeTask t{&job, job.seed, slot.contract_index, slot.contract_episode, i,
                  episode_seed(job.seed, slot.contract_episode), adapter_episode_seed(job.seed, slot.contract_episode), 0};
    EpisodeRecord r = testing::fake_episode_fn()(t);
    r.job_id = job_id(job);
    r.task = job.task;
    r.split = job.split.name;
    r.method = job.method;
    r.method_variant = job.method;
    r.seed = job.seed;
    r.contract_index = slot.contract_index;
    r.episode_index = i;
    r.backbone = job.backbone.name;
    r.backbone_sha256 = job.backbone.sha256;
    return r;
  }

  fs::path dir_;
};

TEST_F(StoreTest, AppendsWholeLinesAndReopens) {
  const JobSpec job = testing::fake_job(5);
  {
    auto s = ResultStore::open(dir_.string(), job);
    EXPECT_EQ(s.episodes_done(), 0);
    EXPECT_EQ(s.jsonl_path(), (dir_ / (job_id(job) + ".jsonl")).string());
    for (int i = 0; i < 3; ++i) s.append(record(job, i));
  }
  const std::string bytes = slurp((dir_ / (job_id(job) + ".jsonl")).string());
  EXPECT_EQ(std::count(bytes.begin(), bytes.end(), '\n'), 3);
  EXPECT_EQ(bytes, to_jsonl_line(record(job, 0)) + "\n" + to_jsonl_line(record(job, 1)) + "\n" +
                       to_jsonl_line(record(job, 2)) + "\n");
  auto s = ResultStore::open(dir_.string(), job);
  EXPECT_EQ(s.episodes_done(), 3);
  EXPECT_EQ(s.records()[2], record(job, 2));
  EXPECT_FALSE(s.complete());
}

TEST_F(StoreTest, AppendRejectsOutOfOrderAndForeignRecords) {
  const JobSpec job = testing::fake_job(5);
  auto s = ResultStore::open(dir_.string(), job);
  EXPECT_THAT([&] { s.append(record(job, 1)); }, ThrowsMessage<InputError>(HasSubstr("episode_index")));
  auto foreign = record(job, 0);
  foreign.method = "no_adapt";
  EXPECT_THAT([&] { s.append(foreign); }, ThrowsMessage<InputError>(HasSubstr("method: record belongs to another job")));
  auto other_id = record(job, 0);
  other_id.job_id = std::string(64, '0');
  EXPECT_THAT([&] { s.append(other_id); }, ThrowsMessage<InputError>(HasSubstr("job_id: record belongs to another job")));
}

TEST_F(StoreTest, RepairsAnUnterminatedTail) {
  const JobSpec job = testing::fake_job(5);
  {
    auto s = ResultStore::open(dir_.string(), job);
    for (int i = 0; i < 3; ++i) s.append(record(job, i));
  }
  const std::string path = (dir_ / (job_id(job) + ".jsonl")).string();
  const std::string good = slurp(path);
  fs::resize_file(path, good.size() - 25);  // cut record 2 mid-line
  std::ostringstream log;
  auto s = ResultStore::open(dir_.string(), job, {false, &log});
  EXPECT_EQ(s.episodes_done(), 2);
  EXPECT_GT(s.repaired_bytes(), 0);
  EXPECT_THAT(log.str(), HasSubstr("repaired a torn last line"));
  const std::string after = slurp(path);
  EXPECT_EQ(after, good.substr(0, good.rfind('\n', good.size() - 2) + 1));
}

// only an unterminated last line is a torn write: a complete line that does not parse was written
// whole (or edited), so it is an error naming file and line and the file is never changed
TEST_F(StoreTest, ACompleteUnparsableLastLineIsAnErrorAndTheFileIsUntouched) {
  const JobSpec job = testing::fake_job(5);
  {
    auto s = ResultStore::open(dir_.string(), job);
    s.append(record(job, 0));
  }
  const std::string path = (dir_ / (job_id(job) + ".jsonl")).string();
  {
    std::ofstream f(path, std::ios::app | std::ios::binary);
    f << std::string(40, '\0') << "\n";  // a zero-filled block, newline-terminated
  }
  const std::string before = slurp(path);
  EXPECT_THAT([&] { ResultStore::open(dir_.string(), job); },
              ThrowsMessage<InputError>(HasSubstr(path + ":2: ")));
  EXPECT_EQ(slurp(path), before);
  // the same bytes without their newline are a torn tail, cut away
  fs::resize_file(path, before.size() - 1);
  auto s = ResultStore::open(dir_.string(), job);
  EXPECT_EQ(s.episodes_done(), 1);
  EXPECT_EQ(slurp(path), before.substr(0, before.size() - 41));
}

TEST_F(StoreTest, CorruptMiddleLineIsAnErrorAndTheFileIsUntouched) {
  const JobSpec job = testing::fake_job(5);
  {
    auto s = ResultStore::open(dir_.string(), job);
    for (int i = 0; i < 3; ++i) s.append(record(job, i));
  }
  const std::string path = (dir_ / (job_id(job) + ".jsonl")).string();
  std::string bytes = slurp(path);
  bytes[bytes.find('\n') + 1] = '#';  // break line 2
  {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f << bytes << "{\"torn";  // plus a torn tail that must NOT be repaired when failing
  }
  EXPECT_THAT([&] { ResultStore::open(dir_.string(), job); },
              ThrowsMessage<InputError>(HasSubstr(path + ":2: not valid JSON")));
  EXPECT_EQ(slurp(path), bytes + "{\"torn");
}

TEST_F(StoreTest, RecordsOfAnotherJobOrOutOfOrderAreErrors) {
  const JobSpec job = testing::fake_job(5);
  const std::string path = (dir_ / (job_id(job) + ".jsonl")).string();
  fs::create_directories(dir_);
  const JobSpec other = testing::fake_job(5, "no_adapt");
  {
    std::ofstream f(path, std::ios::binary);
    f << to_jsonl_line(record(other, 0)) << "\n" << to_jsonl_line(record(other, 1)) << "\n";
  }
  const std::string before = slurp(path);
  EXPECT_THAT([&] { ResultStore::open(dir_.string(), job); },
              ThrowsMessage<InputError>(HasSubstr(path + ":1: job_id: record belongs to another job")));
  EXPECT_EQ(slurp(path), before);
  {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f << to_jsonl_line(record(job, 0)) << "\n" << to_jsonl_line(record(job, 2)) << "\n" << to_jsonl_line(record(job, 1)) << "\n";
  }
  EXPECT_THAT([&] { ResultStore::open(dir_.string(), job); },
              ThrowsMessage<InputError>(HasSubstr(":2: episode_index: records must be episodes 0..k-1 in order (got 2, expected 1)")));
}

TEST_F(StoreTest, SecondOpenOfARunningJobIsRefused) {
  const JobSpec job = testing::fake_job(5);
  auto first = ResultStore::open(dir_.string(), job);
  EXPECT_THAT([&] { ResultStore::open(dir_.string(), job); },
              ThrowsMessage<InputError>(HasSubstr("another process is running this job")));
}

TEST_F(StoreTest, SummaryCountsAndIntervals) {
  const JobSpec job = testing::fake_job(6);
  std::vector<EpisodeRecord> recs;
  for (int i = 0; i < 4; ++i) recs.push_back(record(job, i));
  recs[0].success_once = true;
  recs[1].success_once = false;
  recs[2].success_once = true;
  recs[3].success_once = true;
  recs[3].safety_flags = {"workspace_exit", "non_finite_action"};
  recs[1].safety_flags = {"workspace_exit"};
  recs[2].safety_flags = {};
  recs[0].safety_flags = {};
  const auto s = make_job_summary(job, recs, 4, 1.5, "stopped");
  EXPECT_EQ(s["episodes_done"], 4);
  EXPECT_EQ(s["episodes_requested"], 6);
  EXPECT_EQ(s["complete"], false);
  EXPECT_EQ(s["success_once"]["successes"], 3);
  EXPECT_EQ(s["success_once"]["lower"].get<double>(), wilson_interval(3, 4).lower);
  EXPECT_EQ(s["safety_flag_counts"]["workspace_exit"], 2);
  EXPECT_EQ(s["safety_flag_counts"]["non_finite_action"], 1);
  EXPECT_EQ(s["episodes_with_safety_flags"], 2);
  EXPECT_EQ(s["per_contract"].size(), 3u);
  // episodes 0..2 are block 0 (each contract once), episode 3 opens block 1 with one contract
  const std::int64_t twice = episode_slot(job.seed, 3, 3).contract_index;
  for (std::size_t c = 0; c < 3; ++c)
    EXPECT_EQ(s["per_contract"][c]["episodes"], static_cast<std::int64_t>(c) == twice ? 2 : 1) << "contract " << c;
  EXPECT_EQ(s["message"], "stopped");
  EXPECT_EQ(s["job_id"], job_id(job));
  const auto empty = make_job_summary(job, {}, 0, 0.0, "not run");
  EXPECT_TRUE(empty["success_once"].is_null());
}

}  // namespace
}  // namespace actionshift::eval
