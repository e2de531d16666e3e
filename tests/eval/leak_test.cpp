// The hidden contract cannot be read from what an agent receives (the honest-verdicts issue, item 0).
//
// Played as a cheating researcher would: a backbone that tabulates the first observation of every
// episode of the runner's public schedule (the job's seed is known) for every contract of the split, and
// acts as the oracle when its first observation names one contract; and an adapter that does the same
// with what an adapter receives (its episode seed and the tool rotation R). Under the schedule of job
// schema 2.0 (round-robin dealing, per-contract initial states) the same cheater identifies every
// contract and scores at the oracle's level, which shows the attack is real; under today's paired
// schedule every first observation is shared by all contracts of the split, so the cheater scores
// exactly the no_adapt floor.
#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>

namespace actionshift::eval {
namespace {

namespace fs = std::filesystem;

std::string key_of(const Eigen::VectorXd& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), static_cast<std::size_t>(v.size()) * sizeof(double));
}
std::string key_of(const Mat3& R, std::uint64_t adapter_seed) {
  std::string k(reinterpret_cast<const char*>(R.data()), 9 * sizeof(double));
  k.append(reinterpret_cast<const char*>(&adapter_seed), sizeof adapter_seed);
  return k;
}

// the schedule of job schema 2.0, re-implemented here only to show that the cheaters work when the
// information is there: contract i mod n, environment seed from (seed, contract, episode index)
std::uint64_t legacy_episode_seed(std::uint64_t seed, std::int64_t c, std::int64_t i) {
  return splitmix64(splitmix64(splitmix64(seed) ^ static_cast<std::uint64_t>(c)) ^ static_cast<std::uint64_t>(i));
}

struct Episode {
  std::int64_t contract;
  std::uint64_t env_seed, adapter_seed;
};

std::vector<Episode> schedule(const JobSpec& job, bool legacy) {
  std::vector<Episode> out;
  for (std::int64_t i = 0; i < job.episodes; ++i) {
    if (legacy) {
      const std::int64_t c = i % job.split.contracts;
      out.push_back({c, legacy_episode_seed(job.seed, c, i), adapter_episode_seed(job.seed, i / job.split.contracts)});
    } else {
      const EpisodeTask t = episode_task(job, i);
      out.push_back({t.contract_index, t.episode_seed, t.adapter_seed});
    }
  }
  return out;
}

// first observation (backbone's key) and (R, adapter seed) (adapter's key) -> the contracts they occur with
struct Tables {
  std::map<std::string, std::set<std::int64_t>> by_obs, by_adapter_input;
};

Tables tabulate(const JobSpec& job, const std::vector<Episode>& episodes, const adapt::TcpSlice& slice) {
  Tables t;
  sim::Env env(sim::EnvModel::make(sim::parse_task(job.task)));
  for (const auto& e : episodes) {
    const Eigen::VectorXd obs = env.reset(e.env_seed);
    t.by_obs[key_of(obs)].insert(e.contract);
    t.by_adapter_input[key_of(adapt::tcp_rotation(obs, slice), e.adapter_seed)].insert(e.contract);
  }
  return t;
}

// acts as the oracle of the contract its first observation names, honestly otherwise
class CheatingBackbone : public policy::Policy {
 public:
  CheatingBackbone(std::shared_ptr<const policy::Policy> honest, std::shared_ptr<const Tables> tables,
                   std::vector<Contract> contracts, adapt::TcpSlice slice)
      : honest_(honest->clone()), proto_(std::move(honest)), tables_(std::move(tables)), contracts_(std::move(contracts)), slice_(slice) {}
  void reset() override {
    honest_->reset();
    first_ = true;
    oracle_.reset();
  }
  Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) override {
    const Eigen::VectorXd o = obs;
    if (first_) {
      first_ = false;
      const auto it = tables_->by_obs.find(key_of(o));
      if (it != tables_->by_obs.end() && it->second.size() == 1) {
        oracle_.emplace(contracts_.at(static_cast<std::size_t>(*it->second.begin())));
        oracle_->begin_episode(0);
        ++identified;
      }
    }
    const Action intent = honest_->act(obs);
    if (!oracle_) return intent;
    const Mat3 R = adapt::tcp_rotation(o, slice_);
    const Action raw = oracle_->encode(intent, R);
    oracle_->observe(raw, Pose6::Zero(), R);
    return raw;
  }
  std::string name() const override { return proto_->name(); }
  std::string sha256() const override { return proto_->sha256(); }
  sim::TaskId task() const override { return proto_->task(); }
  std::unique_ptr<policy::Policy> clone() const override {
    return std::make_unique<CheatingBackbone>(proto_, tables_, contracts_, slice_);
  }
  int identified{0};

 private:
  std::unique_ptr<policy::Policy> honest_;
  std::shared_ptr<const policy::Policy> proto_;
  std::shared_ptr<const Tables> tables_;
  std::vector<Contract> contracts_;
  adapt::TcpSlice slice_;
  bool first_{true};
  std::optional<adapt::OracleAdapter> oracle_;
};

// an adapter that receives only what the runner gives every adapter (its seed, then R at each step)
class CheatingAdapter : public adapt::Adapter {
 public:
  CheatingAdapter(const Tables& t, const std::vector<Contract>& contracts) : tables_(t), contracts_(contracts) {}
  std::string name() const override { return "cheat"; }
  void begin_episode(std::uint64_t seed) override {
    seed_ = seed;
    first_ = true;
    oracle_.reset();
  }
  Action encode(const Action& canonical, const Mat3& R) override {
    if (first_) {
      first_ = false;
      const auto it = tables_.by_adapter_input.find(key_of(R, seed_));
      if (it != tables_.by_adapter_input.end() && it->second.size() == 1) {
        oracle_.emplace(contracts_.at(static_cast<std::size_t>(*it->second.begin())));
        oracle_->begin_episode(0);
        ++identified;
      }
    }
    return oracle_ ? oracle_->encode(canonical, R) : canonical;
  }
  void observe(const Action& raw, const Pose6& response, const Mat3& R) override {
    if (oracle_) oracle_->observe(raw, response, R);
  }
  int identified{0};

 private:
  const Tables& tables_;
  const std::vector<Contract>& contracts_;
  std::uint64_t seed_{0};
  bool first_{true};
  std::optional<adapt::OracleAdapter> oracle_;
};

// the runner's episode loop for an adapter supplied here (what Context::run does with a registry method)
int successes(const JobSpec& job, const std::vector<Episode>& episodes, const std::vector<Contract>& contracts,
              adapt::Adapter& adapter, const adapt::TcpSlice& slice) {
  const auto model = sim::EnvModel::make(sim::parse_task(job.task));
  const auto backbone = policy::make_policy(job.backbone.name, sim::parse_task(job.task));
  int wins = 0;
  for (const auto& e : episodes) {
    sim::HiddenContractEnv env(model, contracts.at(static_cast<std::size_t>(e.contract)));
    Eigen::VectorXd obs = env.reset(e.env_seed);
    backbone->reset();
    adapter.begin_episode(e.adapter_seed);
    for (int step = 0; step < env.horizon(); ++step) {
      const Mat3 R = adapt::tcp_rotation(obs, slice);
      const Action raw = adapter.encode(backbone->act(obs), R);
      const sim::StepResult& r = env.step(raw);
      if (r.safety != sim::SafetyFlag::kNone) break;
      adapter.observe(raw, adapt::tcp_response(obs, r.obs, slice), R);
      obs = r.obs;
      if (r.episode_over()) break;
    }
    wins += env.episode().success_once ? 1 : 0;
  }
  return wins;
}

class Leakage : public ::testing::Test {
 protected:
  void SetUp() override {
    JobRequest q;
    q.task = "pick_cube";
    q.split = "reference_seen";
    q.method.name = "no_adapt";
    q.backbone = "expert";
    q.seed = 20260718;
    q.episodes = 16;
    job = resolve_job(q, default_resolver());
    contracts = data::resolve_manifest(job.split.name).contracts();
    slice = tcp_slice(sim::observation_layout(sim::TaskId::kPickCube));
    dir = fs::temp_directory_path() / ("actionshift_leak_" + std::to_string(::getpid()));
    fs::remove_all(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  JobSpec job;
  std::vector<Contract> contracts;
  adapt::TcpSlice slice;
  fs::path dir;
};

TEST_F(Leakage, EveryFirstObservationAndAdapterInputIsSharedByEveryContract) {
  const Tables now = tabulate(job, schedule(job, false), slice);
  for (const auto& [k, cs] : now.by_obs) EXPECT_EQ(static_cast<std::int64_t>(cs.size()), job.split.contracts);
  for (const auto& [k, cs] : now.by_adapter_input) EXPECT_EQ(static_cast<std::int64_t>(cs.size()), job.split.contracts);
  // the control: under schema 2.0 every first observation named its contract
  const Tables legacy = tabulate(job, schedule(job, true), slice);
  for (const auto& [k, cs] : legacy.by_obs) EXPECT_EQ(cs.size(), 1u);
}

TEST_F(Leakage, TheCheatingBackboneScoresTheNoAdaptFloor) {
  const auto expert = std::shared_ptr<const policy::Policy>(policy::make_policy("expert", sim::TaskId::kPickCube));
  // honest no_adapt and the oracle, through the runner
  RunOptions ro;
  ro.threads = 1;
  ro.progress = ProgressMode::off;
  ro.out_dir = (dir / "honest").string();
  run_job(job, make_episode_fn(job), ro);
  JobSpec oracle_job = job;
  oracle_job.method = "oracle";
  ro.out_dir = (dir / "oracle").string();
  run_job(oracle_job, make_episode_fn(oracle_job), ro);

  auto tables = std::make_shared<const Tables>(tabulate(job, schedule(job, false), slice));
  auto cheater = std::make_shared<CheatingBackbone>(expert, tables, contracts, slice);
  ro.out_dir = (dir / "cheat").string();
  const RunResult cheat = run_job(job, make_episode_fn(job, cheater), ro);
  const auto rate = [](const std::string& path) {
    const auto f = read_record_file(path);
    std::vector<bool> s;
    for (const auto& r : f.records) s.push_back(r.success_once);
    return s;
  };
  const auto honest = rate((dir / "honest" / jsonl_file_name(job_id(job))).string());
  const auto oracle = rate((dir / "oracle" / jsonl_file_name(job_id(oracle_job))).string());
  const auto cheated = rate(cheat.jsonl_path);
  ASSERT_EQ(cheated.size(), 16u);
  EXPECT_EQ(cheated, honest) << "the cheating backbone did better than no adaptation";
  // the floor and the ceiling differ on this cell, so equality with the floor is a real statement
  EXPECT_LT(std::count(honest.begin(), honest.end(), true) + 8, std::count(oracle.begin(), oracle.end(), true));

  // the same cheater under the schema-2.0 schedule identifies every contract and reaches the ceiling
  auto legacy_tables = std::make_shared<const Tables>(tabulate(job, schedule(job, true), slice));
  CheatingBackbone legacy(expert, legacy_tables, contracts, slice);
  const auto model = sim::EnvModel::make(sim::TaskId::kPickCube);
  int legacy_wins = 0;
  for (const auto& e : schedule(job, true)) {
    sim::HiddenContractEnv env(model, contracts.at(static_cast<std::size_t>(e.contract)));
    Eigen::VectorXd obs = env.reset(e.env_seed);
    legacy.reset();
    for (int step = 0; step < env.horizon(); ++step) {
      const sim::StepResult& r = env.step(legacy.act(obs));
      obs = r.obs;
      if (r.episode_over() || r.safety != sim::SafetyFlag::kNone) break;
    }
    legacy_wins += env.episode().success_once ? 1 : 0;
  }
  EXPECT_EQ(legacy.identified, 16);
  EXPECT_GE(legacy_wins, 14);
}

TEST_F(Leakage, TheCheatingAdapterScoresTheNoAdaptFloor) {
  const auto now = schedule(job, false);
  const Tables tables = tabulate(job, now, slice);
  CheatingAdapter cheat(tables, contracts);
  adapt::NoAdaptAdapter honest;
  EXPECT_EQ(successes(job, now, contracts, cheat, slice), successes(job, now, contracts, honest, slice));
  EXPECT_EQ(cheat.identified, 0);
  // under the schema-2.0 schedule the same adapter identifies every contract and restores the expert
  const auto legacy = schedule(job, true);
  const Tables legacy_tables = tabulate(job, legacy, slice);
  CheatingAdapter legacy_cheat(legacy_tables, contracts);
  adapt::NoAdaptAdapter legacy_honest;
  const int cheated = successes(job, legacy, contracts, legacy_cheat, slice);
  EXPECT_EQ(legacy_cheat.identified, 16);
  EXPECT_GE(cheated, successes(job, legacy, contracts, legacy_honest, slice) + 8);
}

}  // namespace
}  // namespace actionshift::eval
