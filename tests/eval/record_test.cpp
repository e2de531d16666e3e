#include "actionshift/eval/record.hpp"
#include "actionshift/sim/env.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace actionshift::eval {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

EpisodeRecord sample_record() {
  EpisodeRecord r;
  r.job_id = sha256_hex("job");
  r.task = "pick_cube";
  r.split = "seen";
  r.method = "oracle";
  r.method_variant = "oracle";
  r.seed = 20260718;
  r.contract_index = 1;
  r.contract_sha256 = sha256_hex("contract");
  r.episode_index = 7;
  r.success_once = true;
  r.success_at_end = false;
  r.task_return = 12.5;
  r.steps = 50;
  r.probe_steps = 6;
  r.probe_displacement = 0.0125;
  r.safety_flags = {"workspace_violation"};
  r.backbone = "expert";
  r.backbone_sha256 = sha256_hex("expert");
  return r;
}

TEST(EpisodeRecord, SerialisesAsOneCanonicalLine) {
  const std::string line = to_jsonl_line(sample_record());
  const std::string expected =
      "{\"backbone\":\"expert\",\"backbone_sha256\":\"" + sha256_hex("expert") +
      "\",\"contract_index\":1,\"contract_sha256\":\"" + sha256_hex("contract") +
      "\",\"episode_index\":7,\"job_id\":\"" + sha256_hex("job") +
      "\",\"method\":\"oracle\",\"method_variant\":\"oracle\",\"probe_displacement\":0.0125,\"probe_steps\":6,\"profile\":\"maniskill\",\"return\":12.5,"
      "\"safety_flags\":[\"workspace_violation\"],\"schema_version\":\"2.0\",\"seed\":20260718,\"split\":\"seen\","
      "\"steps\":50,\"success_at_end\":false,\"success_once\":true,\"task\":\"pick_cube\"}";
  EXPECT_EQ(line, expected);
  EXPECT_EQ(line.find('\n'), std::string::npos);
}

TEST(EpisodeRecord, RefusesAFlagOrProfileTheSimulatorDoesNotKnow) {
  // a renamed flag must not pass unnoticed: the name read is checked against sim::kSafetyFlags
  std::string line = to_jsonl_line(sample_record());
  const std::string real = "\"workspace_violation\"";
  std::string bad = line;
  bad.replace(bad.find(real), real.size(), "\"workspace_exit\"");
  EXPECT_THAT([&] { (void)parse_record_line(bad, "results/j.jsonl:3"); },
              ThrowsMessage<InputError>(HasSubstr("results/j.jsonl:3: safety_flags: unknown safety flag 'workspace_exit' (valid: ")));
  bad = line;
  bad.replace(bad.find(real), real.size(), "\"none\"");
  EXPECT_THAT([&] { (void)parse_record_line(bad, "j.jsonl:1"); }, ThrowsMessage<InputError>(HasSubstr("j.jsonl:1: safety_flags: ")));
  bad = line;
  bad.replace(bad.find("\"maniskill\""), 11, "\"physx\"");
  EXPECT_THAT([&] { (void)parse_record_line(bad, "j.jsonl:1"); },
              ThrowsMessage<InputError>(HasSubstr("j.jsonl:1: profile: unknown fidelity profile 'physx'")));
  // every flag the simulator can raise is accepted
  for (const auto& e : sim::kSafetyFlags.entries) {
    if (e.value == sim::SafetyFlag::kNone) continue;
    auto r = sample_record();
    r.safety_flags = {std::string(e.name)};
    EXPECT_EQ(parse_record_line(to_jsonl_line(r), "j.jsonl:1"), r) << e.name;
  }
}

TEST(EpisodeRecord, WholeNumberFloatsKeepTheirDecimalPoint) {
  auto r = sample_record();
  r.task_return = 3.0;
  r.probe_displacement = 0.0;
  const std::string line = to_jsonl_line(r);
  EXPECT_THAT(line, HasSubstr("\"return\":3.0,"));
  EXPECT_THAT(line, HasSubstr("\"probe_displacement\":0.0,"));
}

TEST(EpisodeRecord, RoundTripsThroughItsLine) {
  const auto r = sample_record();
  const std::string line = to_jsonl_line(r);
  const auto back = parse_record_line(line, "f.jsonl:1");
  EXPECT_EQ(back, r);
  EXPECT_EQ(to_jsonl_line(back), line);
  auto r2 = r;
  r2.task_return = 0.1 + 0.2;  // shortest repr round-trips exactly
  EXPECT_EQ(parse_record_line(to_jsonl_line(r2), "x").task_return, 0.1 + 0.2);
}

TEST(EpisodeRecord, ParseErrorsNameSourceLineAndField) {
  const std::string line = to_jsonl_line(sample_record());
  auto with = [&](const std::string& key, const std::string& value) {
    nlohmann::json j = nlohmann::json::parse(line);
    j[key] = nlohmann::json::parse(value);
    return j.dump();
  };
  EXPECT_THAT([&] { parse_record_line(with("episode_index", "-1"), "r.jsonl:4"); },
              ThrowsMessage<InputError>(HasSubstr("r.jsonl:4: episode_index: expected a non-negative integer (got -1)")));
  EXPECT_THAT([&] { parse_record_line(with("steps", "1.5"), "r.jsonl:4"); },
              ThrowsMessage<InputError>(HasSubstr("r.jsonl:4: steps: expected a non-negative integer")));
  EXPECT_THAT([&] { parse_record_line(with("success_once", "1"), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("r.jsonl:2: success_once: expected true or false")));
  EXPECT_THAT([&] { parse_record_line(with("job_id", "\"abc\""), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("r.jsonl:2: job_id: expected 64 lowercase hex digits")));
  EXPECT_THAT([&] { parse_record_line(with("extra", "1"), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("r.jsonl:2: extra: unknown field")));
  EXPECT_THAT([&] { parse_record_line(with("schema_version", "\"9.0\""), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("schema_version: unsupported schema version")));
  // records of 1.x were dealt and seeded differently and ran another entropy/DualABI rule: refused
  EXPECT_THAT([&] { parse_record_line(with("schema_version", "\"1.1\""), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("re-run the job")));
  EXPECT_THAT([&] { parse_record_line(with("method_variant", "\"no_adapt\""), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("method_variant: must be the method's name")));
  EXPECT_THAT([&] { parse_record_line(with("method_variant", "\"oracle_x\""), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("method_variant: must be the method's name")));
  EXPECT_NO_THROW(parse_record_line(with("method_variant", "\"oracle{x=1}\""), "r.jsonl:2"));
  EXPECT_THAT([&] { parse_record_line(with("safety_flags", "[\"workspace_violation\",\"workspace_violation\"]"), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("safety_flags: duplicate flag")));
  EXPECT_THAT([&] { parse_record_line(with("probe_steps", "51"), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("probe_steps: exceeds steps")));
  // a well-formed name that is no task would become a summary cell of its own
  EXPECT_THAT([&] { parse_record_line(with("task", "\"pick_cubes\""), "r.jsonl:2"); },
              ThrowsMessage<InputError>(HasSubstr("r.jsonl:2: task: not a task of this benchmark (got \"pick_cubes\")")));
  nlohmann::json missing = nlohmann::json::parse(line);
  missing.erase("return");
  EXPECT_THAT([&] { parse_record_line(missing.dump(), "r.jsonl:9"); },
              ThrowsMessage<InputError>(HasSubstr("r.jsonl:9: return: missing field")));
  // a torn line names the field the parser was in when the text ended
  EXPECT_THAT([&] { parse_record_line(line.substr(0, 40), "r.jsonl:3"); },
              ThrowsMessage<InputError>(AllOf(HasSubstr("r.jsonl:3: "), HasSubstr("not valid JSON"))));
  EXPECT_THAT([&] { parse_record_line("[1,2]", "r.jsonl:3"); },
              ThrowsMessage<InputError>(HasSubstr("expected a JSON object per line")));
}

TEST(EpisodeRecord, ObsNoiseIsWrittenOnlyWhenNonZero) {
  EXPECT_EQ(to_jsonl_line(sample_record()).find("obs_noise"), std::string::npos);
  EpisodeRecord r = sample_record();
  r.obs_noise = 0.002;
  const std::string line = to_jsonl_line(r);
  EXPECT_THAT(line, HasSubstr("\"obs_noise\":0.002,"));
  EXPECT_EQ(parse_record_line(line, "x.jsonl:1"), r);
  r.obs_noise = -0.002;
  EXPECT_THROW(to_jsonl_line(r), InputError);
}

TEST(EpisodeRecord, RefusesToSerialiseInvalidValues) {
  auto r = sample_record();
  r.task_return = std::nan("");
  EXPECT_THAT([&] { to_jsonl_line(r); }, ThrowsMessage<InputError>(HasSubstr("return: must be finite")));
  r = sample_record();
  r.contract_sha256 = "";
  EXPECT_THAT([&] { to_jsonl_line(r); }, ThrowsMessage<InputError>(HasSubstr("contract_sha256")));
}

TEST(RecordFile, ReadsAllLinesAndReportsATornTail) {
  const auto dir = std::filesystem::temp_directory_path() / "actionshift_record_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "a.jsonl").string();
  auto r0 = sample_record();
  auto r1 = sample_record();
  r1.episode_index = 8;
  {
    std::ofstream f(path);
    f << to_jsonl_line(r0) << "\n" << to_jsonl_line(r1) << "\n" << to_jsonl_line(r1).substr(0, 30);
  }
  EXPECT_THAT([&] { read_record_file(path); }, ThrowsMessage<InputError>(HasSubstr(path + ":3: unterminated last line")));
  const auto rf = read_record_file(path, true);
  EXPECT_TRUE(rf.torn_tail);
  ASSERT_EQ(rf.records.size(), 2u);
  EXPECT_EQ(rf.records[1], r1);
  EXPECT_THAT([&] { read_record_file((dir / "missing.jsonl").string()); },
              ThrowsMessage<InputError>(HasSubstr("missing.jsonl: no such file (expected a results file)")));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace actionshift::eval
