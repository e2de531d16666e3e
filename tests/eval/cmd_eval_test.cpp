// The CLI command functions (apps/actionshift/cmd_eval.cpp) driven directly: exit codes and output.
#include "cmd_eval.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "fake_episode.hpp"
#include "record_sets.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace actionshift::cli {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class CmdEvalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("actionshift_cmd_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
             std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "results");
  }
  void TearDown() override { fs::remove_all(root_); }

  void write_records(const std::string& name, const std::vector<eval::EpisodeRecord>& recs) {
    std::ofstream f(root_ / "results" / name);
    for (const auto& r : recs) f << eval::to_jsonl_line(r) << "\n";
  }
  void write_gate1_results(bool oracle_ok) {
    using eval::testing::make_records;
    const std::vector<std::uint64_t> seeds = {1, 2, 3};
    write_records("o.jsonl", make_records("pick_cube", "seen", "oracle", seeds, 20, [&](int k) { return oracle_ok || k % 2; }));
    write_records("n.jsonl", make_records("pick_cube", "seen", "no_adapt", seeds, 20, [](int) { return false; }));
    write_records("lo.jsonl", make_records("pick_cube", "long_lag", "oracle", seeds, 20, [](int k) { return k % 4 == 0; }));
    write_records("ln.jsonl", make_records("pick_cube", "long_lag", "no_adapt", seeds, 20, [](int) { return false; }));
  }
  std::string results() const { return (root_ / "results").string(); }
  fs::path root_;
};

TEST_F(CmdEvalTest, SummarizeMarkdownAndJson) {
  write_gate1_results(true);
  std::ostringstream out, err;
  EXPECT_EQ(run_summarize({results(), false, ""}, out, err), 0);
  EXPECT_THAT(out.str(), HasSubstr("| pick_cube | seen | oracle | expert | 60 | 1.000 |"));
  std::ostringstream jout;
  const std::string file = (root_ / "summary.json").string();
  EXPECT_EQ(run_summarize({results(), true, file}, jout, err), 0);
  const auto j = nlohmann::json::parse(jout.str());
  EXPECT_EQ(j["cells"].size(), 4u);
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(file)), j);
}

TEST_F(CmdEvalTest, SummarizeBadInputIsOneLineAndExitTwo) {
  {
    std::ofstream f(root_ / "results" / "bad.jsonl");
    f << "{\"nope\":1}\n";
  }
  std::ostringstream out, err;
  EXPECT_EQ(run_summarize({results(), false, ""}, out, err), 2);
  EXPECT_THAT(err.str(), HasSubstr("actionshift: error: "));
  EXPECT_THAT(err.str(), HasSubstr("bad.jsonl:1: nope: unknown field"));
  const std::string text = err.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1);
  std::ostringstream e2;
  EXPECT_EQ(run_summarize({(root_ / "missing").string(), false, ""}, out, e2), 2);
}

TEST_F(CmdEvalTest, Gate1WritesVerdictAndGateCheckCatchesRegression) {
  write_gate1_results(true);
  std::ostringstream out, err;
  const std::string expected = (root_ / "expected.json").string();
  Gate1Options g;
  g.results_dir = results();
  g.verdict_file = expected;
  g.samples = 500;
  EXPECT_EQ(run_gate1(g, out, err), 0) << err.str();
  EXPECT_THAT(out.str(), HasSubstr("| pick_cube | seen | 1.000 ["));
  const auto verdict = nlohmann::json::parse(std::ifstream(expected));
  EXPECT_EQ(verdict["cells"]["pick_cube/seen"]["verdict"], "pass");

  std::ostringstream ok;
  EXPECT_EQ(run_gate_check({expected, results(), ""}, ok, err), 0);
  EXPECT_THAT(ok.str(), HasSubstr("ok pick_cube/seen: expected pass, got pass"));
  EXPECT_THAT(ok.str(), HasSubstr("no verdict regressions"));

  // the oracle gets worse: the committed "pass" regresses
  fs::remove_all(root_ / "results");
  fs::create_directories(root_ / "results");
  write_gate1_results(false);
  std::ostringstream bad;
  EXPECT_EQ(run_gate_check({expected, results(), ""}, bad, err), 1);
  EXPECT_THAT(bad.str(), HasSubstr("REGRESSION pick_cube/seen: expected pass, got fail (oracle 0.5000 below 0.9500)"));
  std::ostringstream g1;
  EXPECT_EQ(run_gate1(g, g1, err), 1);
}

TEST_F(CmdEvalTest, GateCheckBadInput) {
  std::ostringstream out, err;
  EXPECT_EQ(run_gate_check({(root_ / "none.json").string(), results(), ""}, out, err), 2);
  EXPECT_THAT(err.str(), HasSubstr("none.json: no such file (expected a JSON file)"));
  {
    std::ofstream f(root_ / "g0.json");
    f << R"({"gate":"gate0","cells":{"expert/pick_cube":{"verdict":"pass"}}})";
  }
  std::ostringstream e2;
  EXPECT_EQ(run_gate_check({(root_ / "g0.json").string(), results(), ""}, out, e2), 2);
  EXPECT_THAT(e2.str(), HasSubstr("only gate1 and promotion verdicts can be recomputed"));
  // gate0 verdict files compare file to file
  {
    std::ofstream f(root_ / "g0_now.json");
    f << R"({"gate":"gate0","cells":{"expert/pick_cube":{"verdict":"fail","reason":"competence: x"}}})";
  }
  std::ostringstream o3;
  EXPECT_EQ(run_gate_check({(root_ / "g0.json").string(), "", (root_ / "g0_now.json").string()}, o3, err), 1);
  EXPECT_THAT(o3.str(), HasSubstr("REGRESSION expert/pick_cube"));
}

TEST_F(CmdEvalTest, PlanWritesPlanAndSlurmScriptThenRunsJobs) {
  const fs::path yaml = root_ / "smoke.yaml";
  {
    std::ofstream f(yaml);
    f << "name: smoke\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [oracle, no_adapt]\nseeds: [20260718]\n"
         "episodes: 6\nbackbone: expert\n";
  }
  eval::PlanResolver resolver;
  resolver.split = [](const std::string&, const std::string& s) { return eval::SplitRef{s, sha256_hex(s), 3}; };
  resolver.backbone = [](const std::string&, const std::string& b) { return eval::BackboneRef{b, sha256_hex(b)}; };
  PlanOptions p;
  p.experiment_file = yaml.string();
  p.out_dir = results();
  p.slurm = true;
  std::ostringstream out, err;
  ASSERT_EQ(run_plan(p, resolver, out, err), 0) << err.str();
  EXPECT_THAT(out.str(), HasSubstr("plan smoke: 2 jobs"));
  const fs::path plan_file = root_ / "results" / "smoke.plan.json";
  ASSERT_TRUE(fs::exists(plan_file));
  std::ifstream sb(root_ / "results" / "smoke.sbatch");
  std::stringstream script;
  script << sb.rdbuf();
  EXPECT_THAT(script.str(), HasSubstr("#SBATCH --array=0-1\n"));
  EXPECT_THAT(script.str(), HasSubstr(fs::absolute(plan_file).string()));

  // run job 1 of the plan, then all (job 1 is then a no-op)
  int made = 0;
  EpisodeFnFactory factory = [&](const eval::JobSpec& job) {
    ++made;
    if (job.method != "oracle" && job.method != "no_adapt") throw InputError("method", job.method, "unknown method");
    return eval::testing::fake_episode_fn();
  };
  RunPlanOptions r;
  r.plan_file = plan_file.string();
  r.out_dir = (root_ / "out").string();
  r.threads = 2;
  r.progress = "off";
  r.job_index = 1;
  std::ostringstream o1;
  EXPECT_EQ(run_plan_jobs(r, factory, o1, err), 0) << err.str();
  EXPECT_THAT(o1.str(), HasSubstr("pick_cube/seen/no_adapt seed 20260718: 6 episodes run"));
  r.job_index.reset();
  std::ostringstream o2;
  EXPECT_EQ(run_plan_jobs(r, factory, o2, err), 0);
  EXPECT_THAT(o2.str(), HasSubstr("no_adapt seed 20260718: already complete"));
  EXPECT_EQ(made, 3);
  r.job_index = 7;
  std::ostringstream e3;
  EXPECT_EQ(run_plan_jobs(r, factory, o2, e3), 2);
  EXPECT_THAT(e3.str(), HasSubstr("--job-index: out of range (plan has 2 jobs, got 7)"));

  // bad experiment: one line, exit 2
  {
    std::ofstream f(yaml, std::ios::trunc);
    f << "name: smoke\ntasks: [pick_cube]\n";
  }
  std::ostringstream e4;
  EXPECT_EQ(run_plan(p, resolver, out, e4), 2);
  EXPECT_THAT(e4.str(), HasSubstr("smoke.yaml: splits: missing required key"));
  EXPECT_THAT([] { parse_progress_mode("fancy"); }, ::testing::ThrowsMessage<InputError>(HasSubstr("--progress: unknown progress mode 'fancy' (valid: auto, bar, lines, off)")));
}

TEST_F(CmdEvalTest, CommittedExperimentsParse) {
  for (const char* name : {"gate1", "smoke"}) {
    const std::string path = std::string(ACTIONSHIFT_SOURCE_DIR) + "/configs/experiments/" + name + ".yaml";
    const auto ex = eval::load_experiment(path);
    EXPECT_EQ(ex.name, name);
    for (const auto& m : ex.methods) EXPECT_TRUE(m.name == "oracle" || m.name == "no_adapt") << m.name;
  }
  const auto g = eval::load_experiment(std::string(ACTIONSHIFT_SOURCE_DIR) + "/configs/experiments/gate1.yaml");
  EXPECT_EQ(g.tasks, (std::vector<std::string>{"pick_cube", "push_cube", "pull_cube", "stack_cube"}));
  EXPECT_EQ(g.splits, (std::vector<std::string>{"seen", "unseen_composition", "long_lag"}));
  EXPECT_EQ(g.seeds, (std::vector<std::uint64_t>{20260718, 20260719, 20260720}));
  EXPECT_EQ(g.episodes, 256);
  EXPECT_EQ(g.backbone, "expert");
  // 4 × 3 × 2 × 3 = 72 jobs × 256 = 18,432 episodes (issue 5: at least 18,000)
  EXPECT_GE(g.tasks.size() * g.splits.size() * g.methods.size() * g.seeds.size() * static_cast<std::size_t>(g.episodes), 18000u);
}

}  // namespace
}  // namespace actionshift::cli
