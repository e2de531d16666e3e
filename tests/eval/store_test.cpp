#include "actionshift/eval/store.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/eval/summary.hpp"
#include "actionshift/eval/statistics.hpp"
#include "fake_episode.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
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
  recs[3].safety_flags = {"workspace_violation", "nonfinite_action"};
  recs[1].safety_flags = {"workspace_violation"};
  recs[2].safety_flags = {};
  recs[0].safety_flags = {};
  const auto s = make_job_summary(job, recs, 4, 1.5, "stopped", std::string(64, 'a'));
  EXPECT_EQ(s["episodes_done"], 4);
  EXPECT_EQ(s["episodes_requested"], 6);
  EXPECT_EQ(s["complete"], false);
  EXPECT_EQ(s["success_once"]["successes"], 3);
  EXPECT_EQ(s["success_once"]["lower"].get<double>(), wilson_interval(3, 4).lower);
  EXPECT_EQ(s["safety_flag_counts"]["workspace_violation"], 2);
  EXPECT_EQ(s["safety_flag_counts"]["nonfinite_action"], 1);
  EXPECT_EQ(s["episodes_with_safety_flags"], 2);
  EXPECT_EQ(s["per_contract"].size(), 3u);
  // episodes 0..2 are block 0 (each contract once), episode 3 opens block 1 with one contract
  const std::int64_t twice = episode_slot(job.seed, 3, 3).contract_index;
  for (std::size_t c = 0; c < 3; ++c)
    EXPECT_EQ(s["per_contract"][c]["episodes"], static_cast<std::int64_t>(c) == twice ? 2 : 1) << "contract " << c;
  EXPECT_EQ(s["message"], "stopped");
  EXPECT_EQ(s["job_id"], job_id(job));
  const auto empty = make_job_summary(job, {}, 0, 0.0, "not run", sha256_hex(""));
  EXPECT_TRUE(empty["success_once"].is_null());
}

// --- integrity of records and summaries (docs/formats.md §3: records_sha256)

TEST(RecordsSha256, HashesTheFirstNCompleteLines) {
  EXPECT_EQ(records_sha256("a\nbb\nc", 0), sha256_hex(""));
  EXPECT_EQ(records_sha256("a\nbb\nc", 1), sha256_hex("a\n"));
  EXPECT_EQ(records_sha256("a\nbb\nc", 2), sha256_hex("a\nbb\n"));
  EXPECT_EQ(records_sha256("a\nbb\nc", 3), std::nullopt);  // the third line is not terminated
}

class IntegrityTest : public StoreTest {
 protected:
  RunOptions opts() {
    RunOptions o;
    o.out_dir = dir_.string();
    o.threads = 1;
    o.progress = ProgressMode::off;
    std::ostringstream* sink = &log_;
    o.log = sink;
    return o;
  }
  std::string jsonl(const JobSpec& job) { return (dir_ / jsonl_file_name(job_id(job))).string(); }
  std::string summary(const JobSpec& job) { return (dir_ / summary_file_name(job_id(job))).string(); }
  static void write(const std::string& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f << bytes;
  }
  std::ostringstream log_;
};

TEST_F(IntegrityTest, SummaryCarriesTheHashOfTheRecordsBytes) {
  const JobSpec job = testing::fake_job(7);
  run_job(job, testing::fake_episode_fn(), opts());
  const nlohmann::json s = nlohmann::json::parse(slurp(summary(job)));
  EXPECT_EQ(s["schema_version"], "2.0");
  EXPECT_EQ(s["records_sha256"], sha256_hex(slurp(jsonl(job))));
  EXPECT_EQ(load_results(dir_.string()).records.size(), 7u);
}

TEST_F(IntegrityTest, AnEditedRecordOfAFinishedJobIsRefusedByReadersAndResume) {
  const JobSpec job = testing::fake_job(6);
  run_job(job, testing::fake_episode_fn(0), opts());  // no episode succeeds
  std::string bytes = slurp(jsonl(job));
  const auto at = bytes.find("\"success_once\":false");
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, 20, "\"success_once\":true ");  // still a valid record: only the hash can tell
  write(jsonl(job), bytes);
  const auto refused = HasSubstr("records_sha256: the records do not match the summary's hash");
  EXPECT_THAT([&] { load_results(dir_.string()); }, ThrowsMessage<InputError>(refused));
  EXPECT_THAT([&] { load_results(dir_.string()); }, ThrowsMessage<InputError>(HasSubstr(jsonl(job))));
  // a re-run must not claim the job complete
  EXPECT_THAT([&] { run_job(job, testing::fake_episode_fn(0), opts()); }, ThrowsMessage<InputError>(refused));
}

TEST_F(IntegrityTest, AnEditedLastRecordIsNotCutAwayAsATornWrite) {
  const JobSpec job = testing::fake_job(4);
  run_job(job, testing::fake_episode_fn(), opts());
  std::string bytes = slurp(jsonl(job));
  bytes[bytes.size() - 3] = '#';  // the last record no longer parses
  write(jsonl(job), bytes);
  EXPECT_THAT([&] { ResultStore::open(dir_.string(), job); },
              ThrowsMessage<InputError>(HasSubstr("the records do not match the summary's hash")));
  EXPECT_EQ(slurp(jsonl(job)), bytes);  // untouched
}

TEST_F(IntegrityTest, RemovedRecordsAreRefused) {
  const JobSpec job = testing::fake_job(5);
  run_job(job, testing::fake_episode_fn(), opts());
  std::string bytes = slurp(jsonl(job));
  bytes.erase(bytes.rfind('\n', bytes.size() - 2) + 1);  // drop the last record whole
  write(jsonl(job), bytes);
  EXPECT_THAT([&] { load_results(dir_.string()); },
              ThrowsMessage<InputError>(HasSubstr("the file holds 4 complete records but " + job_id(job) + ".summary.json covers 5")));
}

TEST_F(IntegrityTest, TruncatedOrCorruptSummariesAreRefused) {
  const JobSpec job = testing::fake_job(5);
  run_job(job, testing::fake_episode_fn(), opts());
  const std::string good = slurp(summary(job));
  write(summary(job), good.substr(0, good.size() / 2));
  EXPECT_THAT([&] { load_results(dir_.string()); }, ThrowsMessage<InputError>(HasSubstr(summary(job) + ": ")));
  EXPECT_THAT([&] { run_job(job, testing::fake_episode_fn(), opts()); }, ThrowsMessage<InputError>(HasSubstr(summary(job))));
  // a count that is not the records' (the hash still matches: the summary is what was edited)
  nlohmann::json j = nlohmann::json::parse(good);
  j["success_once"]["successes"] = j["success_once"]["successes"].get<int>() == 0 ? 1 : 0;
  write(summary(job), j.dump(2));
  EXPECT_THAT([&] { load_results(dir_.string()); },
              ThrowsMessage<InputError>(HasSubstr("success_once.successes: is ")));
  // a summary of another job under this job's name
  j = nlohmann::json::parse(good);
  j["job"]["seed"] = 1;
  write(summary(job), j.dump(2));
  EXPECT_THAT([&] { load_results(dir_.string()); }, ThrowsMessage<InputError>(HasSubstr("job: is the spec of another job")));
  j = nlohmann::json::parse(good);
  j.erase("records_sha256");
  write(summary(job), j.dump(2));
  EXPECT_THAT([&] { load_results(dir_.string()); }, ThrowsMessage<InputError>(HasSubstr("records_sha256: missing")));
  write(summary(job), good);
  EXPECT_EQ(load_results(dir_.string()).records.size(), 5u);
}

TEST_F(IntegrityTest, RecordsAfterTheSummaryAreReadAndAFinishedJobRewritesAStaleSummary) {
  const JobSpec job = testing::fake_job(6);
  std::atomic<int> calls{0};
  const auto stop_after_3 = [&](const EpisodeTask& t) {
    if (t.episode_index == 3) throw std::runtime_error("boom");
    return testing::fake_episode_fn()(t);
  };
  EXPECT_THROW(run_job(job, stop_after_3, opts()), std::runtime_error);
  // the summary covers 3 records; append the other 3 as a run killed before its summary would
  {
    auto s = ResultStore::open(dir_.string(), job);
    EXPECT_EQ(s.summarized(), 3);
    for (int i = 3; i < 6; ++i) s.append(record(job, i));
  }
  EXPECT_EQ(load_results(dir_.string()).records.size(), 6u);  // the first 3 are verified
  const auto r = run_job(job, testing::fake_episode_fn(), opts());
  EXPECT_TRUE(r.already_complete);
  const nlohmann::json s = nlohmann::json::parse(slurp(summary(job)));
  EXPECT_EQ(s["episodes_done"], 6);
  EXPECT_EQ(s["records_sha256"], sha256_hex(slurp(jsonl(job))));
  (void)calls;
}

TEST_F(IntegrityTest, AVersion1SummaryIsReadByItsCountsAndRewrittenByARerun) {
  const JobSpec job = testing::fake_job(5);
  run_job(job, testing::fake_episode_fn(0), opts());  // no episode succeeds
  nlohmann::json j = nlohmann::json::parse(slurp(summary(job)));
  j.erase("records_sha256");
  j["schema_version"] = "1.0";
  write(summary(job), j.dump(2));
  EXPECT_EQ(load_results(dir_.string()).records.size(), 5u);
  // its counts are still checked: a flipped success is caught
  const std::string bytes = slurp(jsonl(job));
  std::string edited = bytes;
  edited.replace(edited.find("\"success_once\":false"), 20, "\"success_once\":true ");
  write(jsonl(job), edited);
  EXPECT_THAT([&] { load_results(dir_.string()); }, ThrowsMessage<InputError>(HasSubstr("the records do not match the summary")));
  write(jsonl(job), bytes);
  EXPECT_TRUE(run_job(job, testing::fake_episode_fn(), opts()).already_complete);
  EXPECT_EQ(nlohmann::json::parse(slurp(summary(job)))["schema_version"], "2.0");
}

TEST_F(IntegrityTest, ASiblingWithEditedRecordsIsNotAdopted) {
  const JobSpec small = testing::fake_job(4);
  run_job(small, testing::fake_episode_fn(0), opts());
  std::string bytes = slurp(jsonl(small));
  bytes.replace(bytes.find("\"success_once\":false"), 20, "\"success_once\":true ");
  write(jsonl(small), bytes);
  JobSpec big = small;
  big.episodes = 6;
  const auto r = run_job(big, testing::fake_episode_fn(0), opts());
  EXPECT_EQ(r.episodes_run, 6);  // nothing copied from the edited sibling
  EXPECT_EQ(slurp(jsonl(big)).find("\"success_once\":true"), std::string::npos);
}

}  // namespace
}  // namespace actionshift::eval
