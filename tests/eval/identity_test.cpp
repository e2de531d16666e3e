// Job identity beyond the core fields (issue 16): a robot description's and an external policy's
// content hashes enter the id, their paths do not; provenance is recorded but is not identity;
// growing a job copies the episodes already run; summarize merges a grown job with its origin.
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/provenance.hpp"
#include "actionshift/eval/record.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/eval/store.hpp"
#include "actionshift/eval/summary.hpp"
#include "fake_episode.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace actionshift::eval {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

class IdentityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("actionshift_identity_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
             std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  // the fake episode function, counting its calls (the episodes a job actually ran)
  EpisodeFn counting(std::atomic<int>& calls) {
    return [&calls, base = testing::fake_episode_fn()](const EpisodeTask& t) {
      ++calls;
      return base(t);
    };
  }
  RunOptions opts(const std::string& sub) {
    RunOptions o;
    o.out_dir = (root_ / sub).string();
    o.threads = 2;
    o.progress = ProgressMode::off;
    std::ostringstream* sink = &log_;
    o.log = sink;
    return o;
  }
  void write(const fs::path& p, const std::string& text) {
    std::ofstream f(p, std::ios::binary);
    f << text;
  }
  fs::path root_;
  std::ostringstream log_;
};

TEST_F(IdentityTest, RobotHashIsIdentityItsPathsAreNot) {
  JobSpec a = testing::fake_job(8);
  const std::string plain = job_id(a);
  a.robot = RobotRef{sha256_hex("robot-1"), "/x/panda.urdf", {{"pkg", "/x/pkg"}}};
  const std::string with_robot = job_id(a);
  EXPECT_NE(with_robot, plain);
  JobSpec moved = a;
  moved.robot->urdf = "/elsewhere/panda.urdf";
  moved.robot->packages = {{"pkg", "/elsewhere/pkg"}};
  EXPECT_EQ(job_id(moved), with_robot);  // moving the files is not a new job
  JobSpec changed = a;
  changed.robot->sha256 = sha256_hex("robot-2");
  EXPECT_NE(job_id(changed), with_robot);  // changing their content is
  // the spec object keeps the paths; the identity object does not
  EXPECT_EQ(job_to_json(a)["robot"]["urdf"], "/x/panda.urdf");
  EXPECT_FALSE(job_identity_json(a)["robot"].contains("urdf"));
  EXPECT_EQ(job_from_json(job_to_json(a), "spec"), a);
  // no robot: the key is absent, so ids of jobs on the embedded Panda are unchanged
  EXPECT_FALSE(job_to_json(testing::fake_job(8)).contains("robot"));
  nlohmann::json bad = job_to_json(a);
  bad["robot"]["sha256"] = "xyz";
  EXPECT_THAT([&] { job_from_json(bad, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: robot.sha256")));
  bad = job_to_json(a);
  bad["robot"]["extra"] = 1;
  EXPECT_THAT([&] { job_from_json(bad, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("robot.extra: unknown field")));
}

TEST_F(IdentityTest, PolicyFilesContentEntersTheIdAndEditsMakeANewJob) {
  write(root_ / "policy.py", "print('v1')\n");
  write(root_ / "weights.bin", std::string("\0\1\2", 3));
  const std::vector<std::string> files = {(root_ / "policy.py").string(), (root_ / "weights.bin").string()};
  const std::string h1 = files_content_sha256(files);
  EXPECT_EQ(files_content_sha256({files[1], files[0]}), h1);  // order does not matter
  JobSpec a = testing::fake_job(8);
  a.backbone = {"external:python3 policy.py", sha256_hex("external:python3 policy.py")};
  const std::string no_files = job_id(a);
  a.policy_files = PolicyFilesRef{h1, files};
  const std::string v1 = job_id(a);
  EXPECT_NE(v1, no_files);
  write(root_ / "policy.py", "print('v2')\n");  // the user edits the policy
  JobSpec edited = a;
  edited.policy_files->sha256 = files_content_sha256(files);
  EXPECT_NE(edited.policy_files->sha256, h1);
  EXPECT_NE(job_id(edited), v1);
  EXPECT_EQ(job_from_json(job_to_json(a), "spec"), a);
  EXPECT_THAT([&] { files_content_sha256({(root_ / "missing.py").string()}); },
              ThrowsMessage<InputError>(HasSubstr("missing.py: --policy-files: no such file (expected a policy file)")));
  EXPECT_THROW(files_content_sha256({}), InputError);
}

TEST_F(IdentityTest, RecordsAndSummariesCarryProvenanceThatIsNotIdentity) {
  const JobSpec job = testing::fake_job(4);
  const auto r = run_job(job, testing::fake_episode_fn(), opts("p"));
  const Provenance& p = build_provenance();
  EXPECT_FALSE(p.version.empty());
  const RecordFile rf = read_record_file(r.jsonl_path);
  ASSERT_EQ(rf.records.size(), 4u);
  for (const auto& rec : rf.records) {
    EXPECT_EQ(rec.actionshift_version, p.version);
    EXPECT_EQ(rec.git_commit, p.git_commit);
  }
  const nlohmann::json line = nlohmann::json::parse(slurp(r.jsonl_path).substr(0, slurp(r.jsonl_path).find('\n')));
  EXPECT_EQ(line["provenance"]["actionshift_version"], p.version);
  const nlohmann::json summary = nlohmann::json::parse(slurp(r.summary_path));
  EXPECT_EQ(summary["provenance"]["actionshift_version"], p.version);
  EXPECT_FALSE(job_identity_json(job).contains("provenance"));
  // records without provenance (written before it existed) still parse; a malformed one does not
  nlohmann::json old = line;
  old.erase("provenance");
  EXPECT_TRUE(parse_record_line(old.dump(), "old.jsonl:1").actionshift_version.empty());
  nlohmann::json bad = line;
  bad["provenance"] = {{"actionshift_version", 1}};
  EXPECT_THAT([&] { parse_record_line(bad.dump(), "bad.jsonl:1"); },
              ThrowsMessage<InputError>(HasSubstr("bad.jsonl:1: provenance")));
}

TEST_F(IdentityTest, ASiblingWithARecordOfAnotherJobIsNotAdoptedFrom) {
  // an edited sibling record used to be copied into the new job and then accepted by every reader
  std::atomic<int> calls{0};
  const EpisodeFn base = testing::fake_episode_fn();
  const EpisodeFn counted = counting(calls);
  const auto small = run_job(testing::fake_job(4), counted, opts("tampered"));
  std::string text = slurp(small.jsonl_path);
  const std::string id = job_id(testing::fake_job(4));
  text.replace(text.find(id), id.size(), std::string(id.size(), 'c'));  // the first record's job id
  {
    std::ofstream f(small.jsonl_path, std::ios::binary | std::ios::trunc);
    f << text;
  }
  calls = 0;
  const auto grown = run_job(testing::fake_job(6), counted, opts("tampered"));
  EXPECT_EQ(calls.load(), 6) << "nothing is copied from a sibling holding a foreign record";
  EXPECT_EQ(slurp(grown.jsonl_path), slurp(run_job(testing::fake_job(6), base, opts("clean")).jsonl_path));
}

TEST_F(IdentityTest, GrowingAJobRunsOnlyTheMissingEpisodesAndMatchesAFreshRun) {
  std::atomic<int> calls{0};
  const EpisodeFn base = testing::fake_episode_fn();
  const EpisodeFn counted = counting(calls);
  run_job(testing::fake_job(10), counted, opts("grow"));
  EXPECT_EQ(calls.load(), 10);
  calls = 0;
  const auto grown = run_job(testing::fake_job(25), counted, opts("grow"));
  EXPECT_EQ(calls.load(), 15);  // episodes 10..24 only
  EXPECT_EQ(grown.episodes_run, 15);
  EXPECT_THAT(log_.str(), HasSubstr("copied episodes 0..9 from job " + job_id(testing::fake_job(10)).substr(0, 12)));
  const auto fresh = run_job(testing::fake_job(25), base, opts("fresh"));
  EXPECT_EQ(slurp(grown.jsonl_path), slurp(fresh.jsonl_path));  // byte-identical to running 25 from scratch
  // shrinking copies too and runs nothing
  calls = 0;
  run_job(testing::fake_job(4), counted, opts("grow"));
  EXPECT_EQ(calls.load(), 0);
  // a job of another family (other seed) copies nothing
  calls = 0;
  run_job(testing::fake_job(5, "oracle", 7), counted, opts("grow"));
  EXPECT_EQ(calls.load(), 5);

  // summarize merges the overlapping jobs of one family: 25 episodes for seed 20260718, not 39
  const ResultSet rs = load_results((root_ / "grow").string());
  std::int64_t seed_main = 0, seed_7 = 0;
  for (const auto& r : rs.records) (r.seed == 7 ? seed_7 : seed_main) += 1;
  EXPECT_EQ(seed_main, 25);
  EXPECT_EQ(seed_7, 5);
  bool noted = false;
  for (const auto& n : rs.notes) noted = noted || n.find("shared episodes counted once") != std::string::npos;
  EXPECT_TRUE(noted);
  EXPECT_NO_THROW(summarize_records(rs.records));
}

TEST_F(IdentityTest, OverlappingJobsWhoseEpisodesDifferAreNamed) {
  run_job(testing::fake_job(6), testing::fake_episode_fn(100), opts("d"));
  // the same family run by "other code": different outcomes for the same episodes
  fs::create_directories(root_ / "other");
  run_job(testing::fake_job(8), testing::fake_episode_fn(0), opts("other"));
  const std::string id8 = job_id(testing::fake_job(8));
  fs::copy_file(root_ / "other" / (id8 + ".jsonl"), root_ / "d" / (id8 + ".jsonl"));
  fs::copy_file(root_ / "other" / (id8 + ".summary.json"), root_ / "d" / (id8 + ".summary.json"));
  EXPECT_THAT([&] { load_results((root_ / "d").string()); },
              ThrowsMessage<InputError>(HasSubstr("differs between them")));
  // without summaries the jobs are unrelated: the duplicate episode is an error naming both jobs
  fs::remove(root_ / "d" / (id8 + ".summary.json"));
  const ResultSet rs = load_results((root_ / "d").string());
  EXPECT_THAT([&] { summarize_records(rs.records); }, ThrowsMessage<InputError>(HasSubstr("appears in jobs")));
}

}  // namespace
}  // namespace actionshift::eval
