// User methods as plug-ins (docs/methods.md): registration rules, privilege by rung, identity by
// content, and a plug-in run through the library's runner exactly like a built-in method.
#include "actionshift/adapt/plugin.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/record.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/eval/runner.hpp"

#include "separation_probes.hpp"  // docs/examples/method_plugin

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace actionshift::eval {
namespace {

namespace fs = std::filesystem;
using adapt::MethodPlugin;
using adapt::PluginInputs;
using adapt::Rung;

// what a factory was handed, for the privilege checks
struct Seen {
  std::atomic<int> calls{0};
  std::atomic<bool> pool{false}, model{false}, grammar{false};
};

MethodPlugin spy(const std::string& name, Rung rung, std::shared_ptr<Seen> seen) {
  MethodPlugin p;
  p.name = name;
  p.rung = rung;
  p.factory = [seen](const PluginInputs& in) -> std::unique_ptr<adapt::Adapter> {
    ++seen->calls;
    seen->pool = seen->pool || in.pool != nullptr;
    seen->model = seen->model || in.model != nullptr;
    seen->grammar = seen->grammar || in.grammar != nullptr;
    return adapt::make_adapter("no_adapt", nlohmann::json::object(), {});
  };
  return p;
}

JobSpec job_for(const std::string& method, std::int64_t episodes = 4) {
  JobRequest q;
  q.task = "pick_cube";
  q.split = "reference_seen";
  q.method.name = method;
  q.backbone = "expert";
  q.pool = "reference9";
  q.seed = 20260718;
  q.episodes = episodes;
  return resolve_job(q, default_resolver());
}

class Plugin : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("actionshift_plugin_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    ro.threads = 2;
    ro.progress = ProgressMode::off;
    ro.out_dir = (dir / "out").string();
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path dir;
  RunOptions ro;
};

TEST_F(Plugin, RegistrationRefusesBuiltinNamesTheOracleRungAndDuplicates) {
  auto seen = std::make_shared<Seen>();
  EXPECT_THROW((void)adapt::register_method(spy("entropy_probes", Rung::pool, seen)), InputError);
  EXPECT_THROW((void)adapt::register_method(spy("probe_osi", Rung::none, seen)), InputError);
  EXPECT_THROW((void)adapt::register_method(spy("Bad Name", Rung::none, seen)), InputError);
  EXPECT_THROW((void)adapt::register_method(spy("cheat", Rung::oracle, seen)), InputError);
  MethodPlugin no_factory = spy("empty", Rung::none, seen);
  no_factory.factory = nullptr;
  EXPECT_THROW((void)adapt::register_method(no_factory), InputError);
  {
    const auto reg = adapt::register_method(spy("twice", Rung::none, seen));
    EXPECT_THROW((void)adapt::register_method(spy("twice", Rung::none, seen)), InputError);
    EXPECT_EQ(adapt::method_rung("twice"), Rung::none);
  }
  EXPECT_EQ(adapt::find_method_plugin("twice"), nullptr) << "the registration ends with its handle";
  EXPECT_EQ(adapt::method_rung("oracle"), Rung::oracle);
  EXPECT_EQ(adapt::method_rung("grammar_belief"), Rung::grammar);
  EXPECT_EQ(adapt::method_rung("dualabi"), Rung::pool);
  EXPECT_EQ(adapt::method_rung("no_adapt"), Rung::none);
}

TEST_F(Plugin, EachRungReceivesExactlyItsInputs) {
  for (const Rung rung : {Rung::pool, Rung::grammar, Rung::none}) {
    auto seen = std::make_shared<Seen>();
    const auto reg = adapt::register_method(spy("spy_method", rung, seen));
    const JobSpec job = job_for("spy_method");
    EXPECT_EQ(job.pool.has_value(), rung == Rung::pool) << "only the pool rung's job names the pool";
    EXPECT_EQ(job.calibration_sha256.has_value(), rung != Rung::none);
    ASSERT_TRUE(job.method_plugin);
    EXPECT_EQ(job.method_plugin->rung, std::string(adapt::rung_name(rung)));
    run_job(job, make_episode_fn(job), ro);
    EXPECT_EQ(seen->calls.load(), 4) << "one adapter per episode";
    EXPECT_EQ(seen->pool.load(), rung == Rung::pool);
    EXPECT_EQ(seen->model.load(), rung != Rung::none);
    EXPECT_EQ(seen->grammar.load(), rung != Rung::none);
  }
}

TEST_F(Plugin, IdentityIsVersionAndContentNotOnlyTheName) {
  const fs::path code = dir / "method.cpp";
  std::ofstream(code) << "// version A\n";
  auto seen = std::make_shared<Seen>();
  MethodPlugin p = spy("content_method", Rung::none, seen);
  p.files = {code.string()};
  std::string id_a;
  JobSpec job_a;
  {
    const auto reg = adapt::register_method(p);
    job_a = job_for("content_method");
    id_a = job_id(job_a);
    EXPECT_EQ(job_a.method_plugin->files.front(), fs::absolute(code).lexically_normal().string());
  }
  {  // another version of the same code
    MethodPlugin v2 = p;
    v2.version = "2";
    const auto reg = adapt::register_method(v2);
    EXPECT_NE(job_id(job_for("content_method")), id_a);
  }
  std::ofstream(code) << "// version B\n";  // the code changed, its version did not
  {
    const auto reg = adapt::register_method(p);
    EXPECT_NE(job_id(job_for("content_method")), id_a);
    // the old job refuses to run the changed method, before any episode
    EXPECT_THROW(make_episode_fn(job_a), InputError);
  }
  // a job of a user method that is not registered here does not run
  EXPECT_THROW(make_episode_fn(job_a), InputError);
  // the path is recorded, not identity: the same content elsewhere is the same job
  std::ofstream(code) << "// version A\n";
  const fs::path moved = dir / "moved.cpp";
  fs::copy_file(code, moved);
  MethodPlugin there = p;
  there.files = {moved.string()};
  const auto reg = adapt::register_method(there);
  EXPECT_EQ(job_id(job_for("content_method")), id_a);
}

TEST_F(Plugin, BuiltinJobIdsDoNotChange) {
  // the user-method field is absent from built-in jobs, so their ids (and every published page) stay
  const JobSpec job = job_for("entropy_probes");
  EXPECT_FALSE(job.method_plugin);
  EXPECT_FALSE(job_to_json(job)["method"].contains("plugin"));
  // a job spec round-trips with its plug-in identity
  auto seen = std::make_shared<Seen>();
  const auto reg = adapt::register_method(spy("round_trip", Rung::grammar, seen));
  const JobSpec user = job_for("round_trip");
  EXPECT_EQ(job_from_json(job_to_json(user), "test"), user);
  EXPECT_FALSE(job_identity_json(user)["method"]["plugin"].contains("files"));
}

TEST_F(Plugin, TheExamplePlugInRunsThroughTheRunnerLikeABuiltinMethod) {
  const auto reg = adapt::register_method(separation::plugin({ACTIONSHIFT_SOURCE_DIR "/docs/examples/method_plugin/separation_probes.hpp"}));
  const JobSpec job = job_for("separation_probes", 9);
  EXPECT_EQ(method_variant(job), "separation_probes{amplitude=0.5,budget=6}");
  const RunResult r = run_job(job, make_episode_fn(job), ro);
  const auto f = read_record_file(r.jsonl_path);
  ASSERT_EQ(f.records.size(), 9u);
  int wins = 0;
  for (const auto& rec : f.records) {
    EXPECT_EQ(rec.method_variant, "separation_probes{amplitude=0.5,budget=6}");
    EXPECT_EQ(rec.probe_steps, 6);
    wins += rec.success_once ? 1 : 0;
  }
  // one episode per contract of reference_seen: the no_adapt floor solves at most the identity-like ones
  EXPECT_GE(wins, 6) << "the example method should identify most reference contracts";
  // thread count does not change the records
  RunOptions one = ro;
  one.threads = 1;
  one.out_dir = (dir / "one").string();
  const RunResult r1 = run_job(job, make_episode_fn(job), one);
  std::ifstream a(r.jsonl_path), b(r1.jsonl_path);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), std::string(std::istreambuf_iterator<char>(b), {}));
}

}  // namespace
}  // namespace actionshift::eval
