#include "actionshift/eval/job.hpp"

#include "actionshift/core/error.hpp"
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
      "\"pool\":null,\"profile\":\"maniskill\",\"rotation_mode\":\"live\",\"schema_version\":\"2.0\",\"seed\":20260718,"
      "\"split\":{\"contracts\":2,\"name\":\"seen\",\"sha256\":\"" + std::string(64, 'a') + "\"},\"task\":\"pick_cube\"}";
  EXPECT_EQ(job_canonical_json(golden_job()), expected);
  EXPECT_EQ(job_id(golden_job()), sha256_hex(expected));
}

TEST(JobSpec, IdIsStable) {
  // golden: computed independently with Python json.dumps(obj, sort_keys=True, separators=(",",":"))
  // + hashlib.sha256; changes only with a deliberate schema change
  EXPECT_EQ(job_id(golden_job()), "f0052a82b78ea3758c53f716282ca843abb666b8acdb64ec835a8b69d3c6b5dd");
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
              ThrowsMessage<InputError>(HasSubstr("rotation_mode: expected \"live\" or \"identity\"")));
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
  EXPECT_EQ(job_id(j), "f0052a82b78ea3758c53f716282ca843abb666b8acdb64ec835a8b69d3c6b5dd");
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

TEST(JobSpec, FileNamesUseTheFullId) {
  const std::string id = job_id(golden_job());
  EXPECT_EQ(jsonl_file_name(id), id + ".jsonl");
  EXPECT_EQ(summary_file_name(id), id + ".summary.json");
}

TEST(EpisodeLayout, RoundRobinOverContracts) {
  EXPECT_EQ(episode_slot(3, 0).contract_index, 0);
  EXPECT_EQ(episode_slot(3, 4).contract_index, 1);
  EXPECT_EQ(episode_slot(3, 4).contract_episode, 1);
  EXPECT_EQ(episode_slot(3, 8).contract_index, 2);
  EXPECT_EQ(episode_slot(3, 8).contract_episode, 2);
  std::vector<int> per(3, 0);
  for (int i = 0; i < 256; ++i) ++per[static_cast<std::size_t>(episode_slot(3, i).contract_index)];
  EXPECT_EQ(per, (std::vector<int>{86, 85, 85}));
  EXPECT_THROW(episode_slot(0, 1), std::invalid_argument);
}

TEST(EpisodeSeed, IsAPinnedPureFunction) {
  // SplitMix64 reference value: the first output of the generator seeded with 0 is 0xE220A8397B1DCDAF
  EXPECT_EQ(splitmix64(0), 0xE220A8397B1DCDAFull);
  EXPECT_EQ(episode_seed(20260718, 1, 7), episode_seed(20260718, 1, 7));
  EXPECT_EQ(episode_seed(20260718, 1, 7), splitmix64(splitmix64(splitmix64(20260718) ^ 1) ^ 7));
  std::set<std::uint64_t> seeds;
  for (std::uint64_t s : {1ull, 2ull})
    for (int c = 0; c < 4; ++c)
      for (int e = 0; e < 50; ++e) seeds.insert(episode_seed(s, c, e));
  EXPECT_EQ(seeds.size(), 400u);
}

TEST(AdapterEpisodeSeed, DependsOnlyOnSeedAndTheIndexWithinTheContract) {
  // the contract index does not enter: a brute force over a split cannot recover it from the seed
  EXPECT_EQ(adapter_episode_seed(20260718, 3), adapter_episode_seed(20260718, 3));
  EXPECT_NE(adapter_episode_seed(20260718, 3), adapter_episode_seed(20260718, 4));
  EXPECT_NE(adapter_episode_seed(20260718, 3), adapter_episode_seed(20260719, 3));
  // and it is not the environment's seed of any (contract, episode) pair of a small job
  std::set<std::uint64_t> env_seeds;
  for (int c = 0; c < 9; ++c)
    for (int e = 0; e < 90; ++e) env_seeds.insert(episode_seed(20260718, c, e));
  for (int k = 0; k < 10; ++k) EXPECT_EQ(env_seeds.count(adapter_episode_seed(20260718, k)), 0u);
}

}  // namespace
}  // namespace actionshift::eval
