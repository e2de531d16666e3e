#include "actionshift/eval/experiment_yaml.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/plan_io.hpp"
#include "actionshift/eval/slurm.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <set>

namespace actionshift::eval {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

PlanResolver fake_resolver() {
  PlanResolver r;
  r.split = [](const std::string& task, const std::string& split) {
    if (split == "missing") throw InputError("manifests/" + split + ".json", "", "no such split manifest");
    (void)task;
    return SplitRef{split, sha256_hex("manifest:" + split), 2};
  };
  r.backbone = [](const std::string& task, const std::string& name) {
    return BackboneRef{name, sha256_hex(name + ":" + task)};
  };
  r.pool = [](const std::string& name) { return PoolRef{name, sha256_hex("pool:" + name)}; };
  r.check_method = [](const MethodEntry& m) {
    if (m.name != "oracle" && m.name != "no_adapt" && m.name != "fixed_probes")
      throw InputError("method", m.name, "unknown method");
  };
  return r;
}

const char* kYaml = R"(
name: tiny
description: two tasks
tasks: [pick_cube, push_cube]
splits: [seen, long_lag]
methods:
  - oracle
  - name: fixed_probes
    params: {budget: 6, amplitude: 0.5, label: "x", on: true}
seeds: [1, 2, 3]
episodes: 16
backbone: expert
)";

TEST(Experiment, ParsesAllKeys) {
  const Experiment ex = parse_experiment(kYaml, "tiny.yaml");
  EXPECT_EQ(ex.name, "tiny");
  EXPECT_EQ(ex.tasks, (std::vector<std::string>{"pick_cube", "push_cube"}));
  EXPECT_EQ(ex.splits, (std::vector<std::string>{"seen", "long_lag"}));
  ASSERT_EQ(ex.methods.size(), 2u);
  EXPECT_EQ(ex.methods[0].params, "{}");
  EXPECT_EQ(ex.methods[1].params, "{\"amplitude\":0.5,\"budget\":6,\"label\":\"x\",\"on\":true}");
  EXPECT_EQ(ex.seeds, (std::vector<std::uint64_t>{1, 2, 3}));
  EXPECT_EQ(ex.episodes, 16);
  EXPECT_EQ(ex.rotation_mode, "live");
  EXPECT_FALSE(ex.pool);
  EXPECT_EQ(ex.source_sha256, sha256_hex(kYaml));
}

TEST(Experiment, ErrorsNameFileAndField) {
  auto fails = [](const std::string& text, const std::string& needle) {
    EXPECT_THAT([&] { parse_experiment(text, "e.yaml"); }, ThrowsMessage<InputError>(HasSubstr(needle))) << text;
  };
  const std::string base = "name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: 4\nbackbone: expert\n";
  EXPECT_NO_THROW(parse_experiment(base, "e.yaml"));
  fails(base + "colour: red\n", "e.yaml:8: colour: unknown key");
  // yaml-cpp keeps both entries of a repeated key and reads the first: the file is refused instead
  fails(base + "episodes: 8\n", "e.yaml:8: episodes: duplicate key");
  fails("name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [{name: oracle, name: no_adapt}]\nseeds: [1]\nepisodes: 4\n"
        "backbone: expert\n",
        "methods[0].name: duplicate key");
  fails("name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [{name: entropy_probes, params: {budget: 2, budget: 6}}]\n"
        "seeds: [1]\nepisodes: 4\nbackbone: expert\n",
        "methods[0].params.budget: duplicate key");
  fails("name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [oracle]\nseeds: [1]\nbackbone: expert\n",
        "e.yaml: episodes: missing required key");
  fails(base + "rotation_mode: real\n", "rotation_mode: unknown rotation mode 'real' (valid: live, identity)");
  fails("name: x\ntasks: [pick_cube, pick_cube]\nsplits: [seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: 4\nbackbone: expert\n",
        "tasks[1]: duplicate entry");
  fails("name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [oracle]\nseeds: [1, -2]\nepisodes: 4\nbackbone: expert\n",
        "seeds[1]: expected a non-negative integer");
  fails("name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: many\nbackbone: expert\n",
        "episodes: expected a positive integer");
  fails("name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [{name: oracle, budget: 3}]\nseeds: [1]\nepisodes: 4\nbackbone: expert\n",
        "methods[0].budget: unknown key");
  fails("name: x\ntasks: {a: 1}\nsplits: [seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: 4\nbackbone: expert\n",
        "tasks: expected a non-empty list of names");
  fails("name: [unclosed\n", "e.yaml:");
  fails("name: [unclosed\n", "malformed YAML");
  fails("- just\n- a list\n", "expected a mapping");
  EXPECT_THAT([] { load_experiment("/nonexistent/e.yaml"); }, ThrowsMessage<InputError>(HasSubstr("/nonexistent/e.yaml: no such file (expected an experiment file)")));
  // found by the fuzz replay: text that is not UTF-8 (its strings become JSON, whose dump threw
  // nlohmann's type_error 316), a "\ud800" escape (a surrogate), and values echoed with their newlines
  fails(base + "description: caf\xe9\n", "e.yaml:8: not valid UTF-8 (byte offset");
  fails("name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [{name: oracle, params: {k: \"\\ud800\"}}]\nseeds: [1]\n"
        "episodes: 4\nbackbone: expert\n",
        "e.yaml:4: malformed YAML: invalid unicode");  // yaml-cpp refuses the surrogate itself
  fails("name: \"a\\nb\"\ntasks: [pick_cube]\nsplits: [seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: 4\nbackbone: expert\n",
        "name: expected a name of [a-z0-9_.-] (got \"a\\nb\")");
  fails(base + "profile: \"" + std::string(300, 'p') + "\"\n", "profile: unknown fidelity profile 'pppppppppp");
  try {
    parse_experiment(base + "profile: \"" + std::string(300, 'p') + "\"\n", "e.yaml");
  } catch (const InputError& e) {
    EXPECT_LT(std::string(e.what()).size(), 200u) << "a long echo is cut";
  }
}

TEST(Plan, CartesianProductInStableOrder) {
  const Plan plan = make_plan(parse_experiment(kYaml, "tiny.yaml"), fake_resolver());
  ASSERT_EQ(plan.jobs.size(), 2u * 2u * 2u * 3u);
  // tasks outermost, seeds innermost
  EXPECT_EQ(plan.jobs[0].spec.task, "pick_cube");
  EXPECT_EQ(plan.jobs[0].spec.split.name, "seen");
  EXPECT_EQ(plan.jobs[0].spec.method, "oracle");
  EXPECT_EQ(plan.jobs[0].spec.seed, 1u);
  EXPECT_EQ(plan.jobs[1].spec.seed, 2u);
  EXPECT_EQ(plan.jobs[3].spec.method, "fixed_probes");
  EXPECT_EQ(plan.jobs[6].spec.split.name, "long_lag");
  EXPECT_EQ(plan.jobs[12].spec.task, "push_cube");
  EXPECT_EQ(plan.jobs[12].spec.backbone.sha256, sha256_hex("expert:push_cube"));
  std::set<std::string> ids;
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    EXPECT_EQ(plan.jobs[i].index, static_cast<std::int64_t>(i));
    EXPECT_EQ(plan.jobs[i].job_id, job_id(plan.jobs[i].spec));
    ids.insert(plan.jobs[i].job_id);
  }
  EXPECT_EQ(ids.size(), plan.jobs.size());
}

TEST(Plan, SingleJobRequestMatchesThePlanEntry) {
  const Plan plan = make_plan(parse_experiment(kYaml, "tiny.yaml"), fake_resolver());
  JobRequest q;
  q.task = "push_cube";
  q.split = "long_lag";
  q.method = {"fixed_probes", "{\"amplitude\":0.5,\"budget\":6,\"label\":\"x\",\"on\":true}"};
  q.seed = 2;
  q.episodes = 16;
  const JobSpec job = resolve_job(q, fake_resolver());
  EXPECT_EQ(job_id(job), plan.jobs[22].job_id);  // push_cube (12) + long_lag (6) + fixed_probes (3) + seed 2 (1)
  q.method.name = "telepathy";
  EXPECT_THAT([&] { resolve_job(q, fake_resolver()); }, ThrowsMessage<InputError>(HasSubstr("unknown method")));
  q.method.name = "oracle";
  q.episodes = 0;
  EXPECT_THAT([&] { resolve_job(q, fake_resolver()); }, ThrowsMessage<InputError>(HasSubstr("command line: episodes: must be > 0")));
}

TEST(Plan, ResolverErrorsPropagate) {
  auto ex = parse_experiment(kYaml, "tiny.yaml");
  ex.splits.push_back("missing");
  // a resolver knows the name it was given; the message names the experiment file and the entry
  EXPECT_THAT([&] { make_plan(ex, fake_resolver()); },
              ThrowsMessage<InputError>(HasSubstr("tiny.yaml: splits[2]: ")));
  EXPECT_THAT([&] { make_plan(ex, fake_resolver()); }, ThrowsMessage<InputError>(HasSubstr("no such split manifest")));
  ex = parse_experiment(kYaml, "tiny.yaml");
  ex.methods.push_back({"telepathy", "{}"});
  EXPECT_THAT([&] { make_plan(ex, fake_resolver()); }, ThrowsMessage<InputError>(HasSubstr("telepathy: unknown method")));
  EXPECT_THAT([&] { make_plan(ex, fake_resolver()); }, ThrowsMessage<InputError>(HasSubstr("tiny.yaml: methods[2]: ")));
  ex = parse_experiment(kYaml, "tiny.yaml");
  ex.tasks.push_back("pick-cube");
  EXPECT_THAT([&] { make_plan(ex, fake_resolver()); },
              ThrowsMessage<InputError>(HasSubstr("tiny.yaml: tasks[2]: task: unknown task 'pick-cube'")));
}

TEST(Plan, FileRoundTripAndTamperDetection) {
  const Plan plan = make_plan(parse_experiment(kYaml, "tiny.yaml"), fake_resolver());
  const auto dir = std::filesystem::temp_directory_path() / "actionshift_plan_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "tiny.plan.json").string();
  write_plan(path, plan);
  const Plan back = load_plan(path);
  ASSERT_EQ(back.jobs.size(), plan.jobs.size());
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    EXPECT_EQ(back.jobs[i].job_id, plan.jobs[i].job_id);
    EXPECT_EQ(job_id(back.jobs[i].spec), plan.jobs[i].job_id);
  }
  nlohmann::json j = plan_to_json(plan);
  j["jobs"][3]["spec"]["seed"] = 99;
  EXPECT_THAT([&] { plan_from_json(j, "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("p.json: jobs[3].job_id: does not match the hash of its spec")));
  std::filesystem::remove_all(dir);
}

TEST(Plan, SlurmArrayScript) {
  const Plan plan = make_plan(parse_experiment(kYaml, "tiny.yaml"), fake_resolver());
  SlurmOptions o;
  o.plan_path = "/data/plans/tiny plan.json";
  o.out_dir = "/data/results";
  o.executable = "/opt/actionshift/bin/actionshift";
  o.cpus_per_task = 4;
  o.max_parallel = 8;
  const std::string s = slurm_array_script(plan, o);
  EXPECT_THAT(s, HasSubstr("#!/bin/bash\n"));
  EXPECT_THAT(s, HasSubstr("#SBATCH --array=0-23%8\n"));
  EXPECT_THAT(s, HasSubstr("#SBATCH --cpus-per-task=4\n"));
  EXPECT_THAT(s, HasSubstr("job_index=$(( ${ACTIONSHIFT_JOB_OFFSET:-0} + ${SLURM_ARRAY_TASK_ID:?"));
  EXPECT_THAT(s, HasSubstr("'/opt/actionshift/bin/actionshift' run --plan '/data/plans/tiny plan.json' "
                           "--job-index \"${job_index}\" --out '/data/results' --threads"));
  EXPECT_EQ(s.find("--partition"), std::string::npos);
  EXPECT_EQ(s.find("--mem"), std::string::npos);
  EXPECT_EQ(shell_quote("it's"), "'it'\\''s'");
}

TEST(Plan, SlurmChunksStayBelowMaxArraySize) {
  const auto c = slurm_chunks(1008, 1001);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].offset, 0);
  EXPECT_EQ(c[0].count, 1001);  // indices 0..1000 < 1001
  EXPECT_EQ(c[1].offset, 1001);
  EXPECT_EQ(c[1].count, 7);
  EXPECT_EQ(slurm_chunks(24, 24).size(), 1u);
  EXPECT_EQ(slurm_chunks(25, 24).size(), 2u);
  EXPECT_THROW(slurm_chunks(3, 0), std::invalid_argument);
}

TEST(Plan, ChunkedArraysAndAMergeJobWithAfterokDependency) {
  const Plan plan = make_plan(parse_experiment(kYaml, "tiny.yaml"), fake_resolver());  // 24 jobs
  SlurmOptions o;
  o.plan_path = "/p/tiny.plan.json";
  o.out_dir = "/r";
  o.executable = "/bin/actionshift";
  o.mem = "4G";
  o.max_array_size = 10;
  o.script_path = "/r/tiny.sbatch";
  o.merge_script_path = "/r/tiny.merge.sbatch";
  const std::string a = slurm_array_script(plan, o);
  EXPECT_EQ(a.find("#SBATCH --array"), std::string::npos);  // three chunks: the submit script gives --array
  EXPECT_THAT(a, HasSubstr("#SBATCH --mem=4G\n"));
  const std::string sub = slurm_submit_script(plan, o);
  EXPECT_THAT(sub, HasSubstr("sbatch --parsable --array=0-9 --export=ALL,ACTIONSHIFT_JOB_OFFSET=0 '/r/tiny.sbatch'"));
  EXPECT_THAT(sub, HasSubstr("sbatch --parsable --array=0-9 --export=ALL,ACTIONSHIFT_JOB_OFFSET=10 '/r/tiny.sbatch'"));
  EXPECT_THAT(sub, HasSubstr("sbatch --parsable --array=0-3 --export=ALL,ACTIONSHIFT_JOB_OFFSET=20 '/r/tiny.sbatch'"));
  EXPECT_THAT(sub, HasSubstr("--dependency=afterok:\"${dep}\""));
  EXPECT_THAT(sub, HasSubstr("'/r/tiny.merge.sbatch'"));
  const std::string m = slurm_merge_script(plan, o);
  EXPECT_THAT(m, HasSubstr("'/bin/actionshift' summarize '/r' --out '/r/tiny.summary.json' > '/r/tiny.summary.md'"));
  // the tiny experiment has no oracle/no_adapt pair: no Gate 1
  EXPECT_EQ(m.find("gate1"), std::string::npos);
}

TEST(Plan, SlurmTimeMemAndMaxArraySizeParsing) {
  for (const char* ok : {"30", "30:00", "02:00:00", "1-0", "1-12", "2-12:30", "0-01:00:00", "UNLIMITED", "120:00:00"})
    EXPECT_TRUE(valid_slurm_time(ok)) << ok;
  for (const char* bad : {"", "0", "00:00:00", "2h", "1:60", "1:2:3:4", "-1", "1-24", "1-", "1:-5", " 30", "1.5"})
    EXPECT_FALSE(valid_slurm_time(bad)) << bad;
  for (const char* ok : {"4G", "4096", "512M", "1T", "100k"}) EXPECT_TRUE(valid_slurm_mem(ok)) << ok;
  for (const char* bad : {"", "0", "G", "4GB", "-4G", "4.5G"}) EXPECT_FALSE(valid_slurm_mem(bad)) << bad;
  EXPECT_EQ(parse_max_array_size("Configuration data as of x\nMailProg = /bin/mail\nMaxArraySize            = 4\n"), 4u);
  EXPECT_EQ(parse_max_array_size("MaxArraySize = 1001"), 1001u);
  EXPECT_FALSE(parse_max_array_size("MaxJobCount = 10000\n"));
  EXPECT_FALSE(parse_max_array_size("MaxArraySize = lots\n"));
}

}  // namespace
}  // namespace actionshift::eval

namespace actionshift::eval {
namespace {

TEST(Plan, PerSplitPoolsAndMethodsWithoutAPool) {
  const std::string yaml =
      "name: t\ntasks: [pick_cube]\nsplits: [reference_seen, seen]\nmethods: [oracle, fixed_probes]\n"
      "seeds: [1]\nepisodes: 4\nbackbone: expert\npool: {reference_seen: reference9, seen: full}\n";
  const Experiment ex = parse_experiment(yaml, "t.yaml");
  ASSERT_EQ(ex.split_pools.size(), 2u);
  EXPECT_EQ(*ex.split_pools.at("seen"), "full");
  PlanResolver r;
  r.split = [](const std::string&, const std::string& s) { return SplitRef{s, sha256_hex(s), 2}; };
  r.backbone = [](const std::string&, const std::string& b) { return BackboneRef{b, sha256_hex(b)}; };
  r.pool = [](const std::string& p) { return PoolRef{p, sha256_hex("pool:" + p)}; };
  r.method_uses_pool = [](const MethodEntry& m) { return m.name != "oracle"; };
  const Plan plan = make_plan(ex, r);
  ASSERT_EQ(plan.jobs.size(), 4u);
  EXPECT_FALSE(plan.jobs[0].spec.pool);  // reference_seen, oracle
  EXPECT_EQ(plan.jobs[1].spec.pool->name, "reference9");  // reference_seen, fixed_probes
  EXPECT_FALSE(plan.jobs[2].spec.pool);
  EXPECT_EQ(plan.jobs[3].spec.pool->name, "full");
  EXPECT_THAT([&] { parse_experiment(yaml.substr(0, yaml.find("pool:")) + "pool: {seen: full}\n", "t.yaml"); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("pool.reference_seen: missing")));
  EXPECT_THAT([&] { parse_experiment(yaml.substr(0, yaml.find("pool:")) + "pool: {reference_seen: a, seen: b, other: c}\n", "t.yaml"); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("pool.other: names a split that is not in splits")));
}

}  // namespace
}  // namespace actionshift::eval
