#include "actionshift/eval/job.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/core/hash.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <set>

namespace actionshift::eval {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

JobSpec golden_job() {
  JobSpec j;
  j.task = "pick_cube";
  j.split = {"seen", std::string(64, 'a'), 2};
  j.method = "oracle";
  j.method_params = "{}";
  j.backbone = {"expert", std::string(64, 'b')};
  j.rotation_mode = "live";
  j.seed = 20260718;
  j.episodes = 256;
  return j;
}

TEST(JobSpec, CanonicalJsonIsPinned) {
  // checked by eye: sorted keys at every level, no whitespace, null for absent pool/calibration
  const std::string expected =
      "{\"backbone\":{\"name\":\"expert\",\"sha256\":\"" + std::string(64, 'b') +
      "\"},\"calibration_sha256\":null,\"episodes\":256,\"method\":{\"name\":\"oracle\",\"params\":{}},"
      "\"pool\":null,\"profile\":\"maniskill\",\"rotation_mode\":\"live\",\"schema_version\":\"3.0\",\"seed\":20260718,"
      "\"split\":{\"contracts\":2,\"name\":\"seen\",\"sha256\":\"" + std::string(64, 'a') + "\"},\"task\":\"pick_cube\"}";
  EXPECT_EQ(job_canonical_json(golden_job()), expected);
  EXPECT_EQ(job_id(golden_job()), sha256_hex(expected));
}

TEST(JobSpec, IdIsStable) {
  // golden: computed independently with Python json.dumps(obj, sort_keys=True, separators=(",",":"))
  // + hashlib.sha256; changes only with a deliberate schema change
  EXPECT_EQ(job_id(golden_job()), "e59abadf5e6c68cb630ee3b2bea3904e04e12f82e58413eec1e20b5274f7006e");
}

TEST(JobSpec, ProfilesAreTheSimulatorsAndUnknownOnesAreRejected) {
  JobSpec j = golden_job();
  j.profile = "physx";
  try {
    validate_job(j, "plan.json");
    FAIL() << "an unknown profile was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("profile"), std::string::npos) << e.what();
  }
  j.profile = "ideal";
  EXPECT_NO_THROW(validate_job(j));
  const auto back = job_from_json(job_to_json(j), "roundtrip");
  EXPECT_EQ(back.profile, "ideal");
}

TEST(JobSpec, EveryFieldChangesTheId) {
  const std::string base = job_id(golden_job());
  const std::vector<std::pair<const char*, std::function<void(JobSpec&)>>> edits = {
      {"task", [](JobSpec& j) { j.task = "push_cube"; }},
      {"split.name", [](JobSpec& j) { j.split.name = "long_lag"; }},
      {"split.sha256", [](JobSpec& j) { j.split.sha256 = std::string(64, 'c'); }},
      {"split.contracts", [](JobSpec& j) { j.split.contracts = 3; }},
      {"method", [](JobSpec& j) { j.method = "no_adapt"; }},
      {"method_params", [](JobSpec& j) { j.method_params = "{\"probe_budget\":6}"; }},
      {"backbone.name", [](JobSpec& j) { j.backbone.name = "mlp"; }},
      {"backbone.sha256", [](JobSpec& j) { j.backbone.sha256 = std::string(64, 'd'); }},
      {"pool", [](JobSpec& j) { j.pool = PoolRef{"reference9", std::string(64, 'e')}; }},
      {"calibration", [](JobSpec& j) { j.calibration_sha256 = std::string(64, 'f'); }},
      {"rotation_mode", [](JobSpec& j) { j.rotation_mode = "identity"; }},
      {"profile", [](JobSpec& j) { j.profile = "ideal"; }},
      {"seed", [](JobSpec& j) { j.seed = 20260719; }},
      {"episodes", [](JobSpec& j) { j.episodes = 255; }},
  };
  std::set<std::string> ids = {base};
  for (const auto& [name, edit] : edits) {
    JobSpec j = golden_job();
    edit(j);
    EXPECT_TRUE(ids.insert(job_id(j)).second) << name << " did not change the id";
  }
  // a pool with a different hash is a different job too
  JobSpec p1 = golden_job(), p2 = golden_job();
  p1.pool = PoolRef{"reference9", std::string(64, 'e')};
  p2.pool = PoolRef{"reference9", std::string(64, '0')};
  EXPECT_NE(job_id(p1), job_id(p2));
}

TEST(JobSpec, ParamsAreHashedCanonically) {
  JobSpec a = golden_job(), b = golden_job();
  a.method_params = "{\"b\": 1.0, \"a\": 2}";
  b.method_params = "{\"a\":2,\"b\":1.0}";
  EXPECT_EQ(job_id(a), job_id(b));
  b.method_params = "{\"a\":2,\"b\":1}";  // an integer is not a float
  EXPECT_NE(job_id(a), job_id(b));
}

TEST(JobSpec, JsonRoundTrip) {
  JobSpec j = golden_job();
  j.pool = PoolRef{"reference9", std::string(64, 'e')};
  j.calibration_sha256 = std::string(64, 'f');
  j.method_params = "{\"amplitude\":0.5,\"budget\":6}";
  const JobSpec back = job_from_json(job_to_json(j), "plan.json");
  EXPECT_EQ(back, j);
  EXPECT_EQ(job_id(back), job_id(j));
}

TEST(JobSpec, ValidationNamesTheField) {
  auto bad = [](std::function<void(JobSpec&)> edit) {
    JobSpec j = golden_job();
    edit(j);
    return j;
  };
  EXPECT_THAT([&] { validate_job(bad([](JobSpec& j) { j.split.sha256 = "xyz"; }), "cli"); },
              ThrowsMessage<InputError>(HasSubstr("cli: split.sha256: expected 64 lowercase hex digits")));
  EXPECT_THAT([&] { validate_job(bad([](JobSpec& j) { j.episodes = 0; }), "cli"); },
              ThrowsMessage<InputError>(HasSubstr("cli: episodes: must be > 0")));
  EXPECT_THAT([&] { validate_job(bad([](JobSpec& j) { j.rotation_mode = "real"; }), "cli"); },
              ThrowsMessage<InputError>(HasSubstr("cli: rotation_mode: unknown rotation mode 'real' (valid: live, identity)")));
  EXPECT_THAT([&] { validate_job(bad([](JobSpec& j) { j.method_params = "[1]"; }), "cli"); },
              ThrowsMessage<InputError>(HasSubstr("method.params: expected a JSON object")));
  EXPECT_THAT([&] { validate_job(bad([](JobSpec& j) { j.split.contracts = 0; }), "cli"); },
              ThrowsMessage<InputError>(HasSubstr("split.contracts: must be > 0")));
  nlohmann::json j = job_to_json(golden_job());
  j["extra"] = 1;
  EXPECT_THAT([&] { job_from_json(j, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: extra: unknown field")));
}

TEST(JobSpec, ObsNoiseEntersTheSpecAndTheIdOnlyWhenNonZero) {
  JobSpec j = golden_job();
  j.obs_noise = 0.0;  // off: the spec, its canonical text and its id are those of every earlier job
  EXPECT_FALSE(job_to_json(j).contains("obs_noise"));
  EXPECT_EQ(job_id(j), "e59abadf5e6c68cb630ee3b2bea3904e04e12f82e58413eec1e20b5274f7006e");
  j.obs_noise = 0.005;
  EXPECT_THAT(job_canonical_json(j), HasSubstr("\"obs_noise\":0.005,"));
  EXPECT_NE(job_id(j), job_id(golden_job()));
  JobSpec k = j;
  k.obs_noise = 0.01;
  EXPECT_NE(job_id(k), job_id(j));
  const JobSpec back = job_from_json(job_to_json(j), "plan.json");
  EXPECT_EQ(back, j);
  EXPECT_EQ(job_id(back), job_id(j));
  for (double bad : {-0.001, std::nan(""), HUGE_VAL, 0.2}) {
    JobSpec b = golden_job();
    b.obs_noise = bad;
    EXPECT_THAT([&] { validate_job(b, "cli"); }, ThrowsMessage<InputError>(HasSubstr("cli: obs_noise: must be a finite sigma in [0, 0.1]")))
        << bad;
  }
  nlohmann::json text = job_to_json(j);
  text["obs_noise"] = "5mm";
  EXPECT_THAT([&] { job_from_json(text, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: obs_noise: expected a number")));
  text["obs_noise"] = -1.0;
  EXPECT_THAT([&] { job_from_json(text, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: obs_noise: must be")));
}

TEST(JobSpec, HorizonEntersTheSpecAndTheIdOnlyWhenNonZero) {
  JobSpec j = golden_job();
  j.horizon = 0;  // the task's: the spec, its canonical text and its id are those of every earlier job
  EXPECT_FALSE(job_to_json(j).contains("horizon"));
  EXPECT_EQ(job_id(j), "e59abadf5e6c68cb630ee3b2bea3904e04e12f82e58413eec1e20b5274f7006e");
  j.horizon = 100;
  EXPECT_THAT(job_canonical_json(j), HasSubstr("\"horizon\":100,"));
  EXPECT_NE(job_id(j), job_id(golden_job()));
  const JobSpec back = job_from_json(job_to_json(j), "plan.json");
  EXPECT_EQ(back, j);
  EXPECT_EQ(job_id(back), job_id(j));
  for (int bad : {-1, sim::kMaxHorizon + 1}) {
    JobSpec b = golden_job();
    b.horizon = bad;
    EXPECT_THAT([&] { validate_job(b, "cli"); }, ThrowsMessage<InputError>(HasSubstr("cli: horizon: must be 0 (the task's) or 1 to 10000")))
        << bad;
  }
  nlohmann::json text = job_to_json(j);
  text["horizon"] = 99.5;
  EXPECT_THAT([&] { job_from_json(text, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: horizon: expected an integer")));
  text["horizon"] = "100";
  EXPECT_THAT([&] { job_from_json(text, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: horizon: expected an integer")));
  text["horizon"] = 1e12;
  EXPECT_THAT([&] { job_from_json(text, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: horizon")));
  text["horizon"] = std::int64_t{20000000000};
  EXPECT_THAT([&] { job_from_json(text, "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json: horizon: must be 0")));
}

TEST(JobSpec, ManifestPathsAreRecordedNotHashed) {
  JobSpec plain = golden_job();
  plain.pool = PoolRef{"reference9", std::string(64, 'e')};
  JobSpec filed = plain;
  filed.split.path = "/data/my dir/custom-split.json";
  filed.pool->path = "/data/custom pool.json";
  // the content hash is the identity: a file of any name or place is the job of the same manifest
  EXPECT_EQ(job_id(filed), job_id(plain));
  EXPECT_EQ(job_canonical_json(filed), job_canonical_json(plain));
  const nlohmann::json j = job_to_json(filed);
  EXPECT_EQ(j["split"]["path"], "/data/my dir/custom-split.json");
  EXPECT_EQ(j["pool"]["path"], "/data/custom pool.json");
  EXPECT_FALSE(job_to_json(plain)["split"].contains("path"));  // built-in splits: the spec is as before
  EXPECT_FALSE(job_identity_json(filed)["split"].contains("path"));
  EXPECT_FALSE(job_identity_json(filed)["pool"].contains("path"));
  EXPECT_EQ(job_from_json(j, "t"), filed);
  nlohmann::json rel = j;
  rel["split"]["path"] = "custom-split.json";
  EXPECT_THAT([&] { job_from_json(rel, "plan.json"); },
              ThrowsMessage<InputError>(HasSubstr("plan.json: split.path: must be an absolute path")));
  rel["split"]["path"] = "";
  EXPECT_THAT([&] { job_from_json(rel, "plan.json"); }, ThrowsMessage<InputError>(HasSubstr("split.path: must not be empty")));
}

TEST(JobSpec, FileNamesUseTheFullId) {
  const std::string id = job_id(golden_job());
  EXPECT_EQ(jsonl_file_name(id), id + ".jsonl");
  EXPECT_EQ(summary_file_name(id), id + ".summary.json");
}

TEST(EpisodeLayout, EveryContractOncePerBlockInASeededOrder) {
  // each block of n episodes runs every contract once; the order within a block is a permutation
  for (std::int64_t n : {1, 3, 32}) {
    for (std::int64_t b = 0; b < 5; ++b) {
      std::set<std::int64_t> seen;
      for (std::int64_t p = 0; p < n; ++p) {
        const auto slot = episode_slot(20260718, n, b * n + p);
        EXPECT_EQ(slot.contract_episode, b);
        seen.insert(slot.contract_index);
      }
      EXPECT_EQ(static_cast<std::int64_t>(seen.size()), n);
      EXPECT_EQ(*seen.begin(), 0);
      EXPECT_EQ(*seen.rbegin(), n - 1);
    }
  }
  std::vector<int> per(3, 0);
  for (int i = 0; i < 256; ++i) ++per[static_cast<std::size_t>(episode_slot(20260718, 3, i).contract_index)];
  for (int c : per) EXPECT_TRUE(c == 85 || c == 86) << c;
  EXPECT_EQ(per[0] + per[1] + per[2], 256);
  // the order is not round-robin and differs between blocks and seeds (32! orders: a collision is
  // astronomically unlikely, so these are exact statements about the pinned function)
  EXPECT_NE(deal_permutation(20260718, 32, 0), deal_permutation(20260718, 32, 1));
  EXPECT_NE(deal_permutation(20260718, 32, 0), deal_permutation(20260719, 32, 0));
  std::vector<std::int64_t> identity(32);
  for (int k = 0; k < 32; ++k) identity[static_cast<std::size_t>(k)] = k;
  EXPECT_NE(deal_permutation(20260718, 32, 0), identity);
  // pinned: the first block of seed 20260718 over 3 contracts
  EXPECT_EQ(deal_permutation(20260718, 3, 0), deal_permutation(20260718, 3, 0));
  EXPECT_THROW(episode_slot(1, 0, 1), std::invalid_argument);
  EXPECT_THROW(episode_slot(1, 3, -1), std::invalid_argument);
}

TEST(EpisodeSeed, IsAPinnedPureFunctionOfSeedAndBlock) {
  // SplitMix64 reference value: the first output of the generator seeded with 0 is 0xE220A8397B1DCDAF
  EXPECT_EQ(splitmix64(0), 0xE220A8397B1DCDAFull);
  EXPECT_EQ(episode_seed(20260718, 7), splitmix64(splitmix64(splitmix64(20260718) ^ 0x696e6974737461ull) ^ 7));
  std::set<std::uint64_t> seeds;
  for (std::uint64_t s : {1ull, 2ull})
    for (int e = 0; e < 200; ++e) seeds.insert(episode_seed(s, e));
  EXPECT_EQ(seeds.size(), 400u);
}

TEST(EpisodeSeed, EveryContractOfABlockStartsFromTheSameState) {
  // the paired design: the environment's seed names the block, never the contract
  JobSpec job;
  job.seed = 20260718;
  job.split.contracts = 32;
  job.episodes = 96;
  for (std::int64_t i = 0; i < job.episodes; ++i) {
    const auto slot = episode_slot(job.seed, 32, i);
    EXPECT_EQ(episode_seed(job.seed, slot.contract_episode), episode_seed(job.seed, i / 32));
  }
}

TEST(AdapterEpisodeSeed, DependsOnlyOnSeedAndTheBlock) {
  EXPECT_EQ(adapter_episode_seed(20260718, 3), adapter_episode_seed(20260718, 3));
  EXPECT_NE(adapter_episode_seed(20260718, 3), adapter_episode_seed(20260718, 4));
  EXPECT_NE(adapter_episode_seed(20260718, 3), adapter_episode_seed(20260719, 3));
  // and it is not the environment's seed of any block of a long job
  std::set<std::uint64_t> env_seeds;
  for (int e = 0; e < 1000; ++e) env_seeds.insert(episode_seed(20260718, e));
  for (int k = 0; k < 1000; ++k) EXPECT_EQ(env_seeds.count(adapter_episode_seed(20260718, k)), 0u);
}

}  // namespace
}  // namespace actionshift::eval
