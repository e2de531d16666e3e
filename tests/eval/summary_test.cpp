#include "actionshift/eval/summary.hpp"

#include "actionshift/core/error.hpp"
#include "record_sets.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace actionshift::eval {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using testing::concat;
using testing::make_records;

TEST(Summary, GroupsByCellWithPerSeedRatesAndFlags) {
  auto oracle = make_records("pick_cube", "seen", "oracle", {1, 2}, 10, [](int k) { return k != 3; });
  oracle[0].probe_steps = 4;
  oracle[0].probe_displacement = 0.02;
  oracle[1].safety_flags = {"workspace_violation"};
  oracle[12].safety_flags = {"workspace_violation", "nonfinite_state"};
  oracle[15].success_once = false;  // seed 2, k = 5
  const auto none = make_records("pick_cube", "seen", "no_adapt", {1}, 10, [](int) { return false; });
  const auto cells = summarize_records(concat(none, oracle));
  ASSERT_EQ(cells.size(), 2u);
  // sorted: no_adapt before oracle
  EXPECT_EQ(cells[0].key.method, "no_adapt");
  const CellSummary& c = cells[1];
  EXPECT_EQ(c.key.method, "oracle");
  EXPECT_EQ(c.episodes, 20);
  EXPECT_EQ(c.success_once.successes, 17);
  EXPECT_EQ(c.success_once, wilson_interval(17, 20));
  ASSERT_EQ(c.per_seed.size(), 2u);
  EXPECT_EQ(c.per_seed[0].successes, 9);
  EXPECT_EQ(c.per_seed[1].successes, 8);
  EXPECT_DOUBLE_EQ(c.per_seed[1].rate, 0.8);
  EXPECT_DOUBLE_EQ(c.mean_probe_steps, 4.0 / 20);
  EXPECT_DOUBLE_EQ(c.mean_probe_displacement, 0.02 / 20);
  EXPECT_EQ(c.safety_flags.at("workspace_violation"), 2);
  EXPECT_EQ(c.safety_flags.at("nonfinite_state"), 1);
  EXPECT_EQ(c.episodes_with_safety_flags, 2);
  EXPECT_EQ(c.jobs.size(), 2u);

  const auto j = summary_to_json(cells);
  EXPECT_EQ(j["cells"][1]["success_once"]["successes"], 17);
  EXPECT_EQ(j["cells"][1]["per_seed"][1]["seed"], 2);
  const std::string md = summary_to_markdown(cells);
  EXPECT_THAT(md, HasSubstr("| pick_cube | seen | oracle | expert | 20 | 0.850 | ["));
  EXPECT_THAT(md, HasSubstr("1: 0.900, 2: 0.800"));
  EXPECT_THAT(md, HasSubstr("nonfinite_state 1, workspace_violation 2"));
}

TEST(Summary, DuplicateEpisodesInACellAreAnError) {
  const auto a = make_records("pick_cube", "seen", "oracle", {1}, 4, [](int) { return true; });
  auto b = a;
  for (auto& r : b) r.job_id = sha256_hex("another job");
  EXPECT_THAT([&] { summarize_records(concat(a, b)); },
              ThrowsMessage<InputError>(HasSubstr("pick_cube/seen/oracle: episode (seed 1, contract 0, episode 0) appears in jobs")));
}

TEST(Summary, LoadsEveryJsonlOfADirectory) {
  const auto dir = std::filesystem::temp_directory_path() / "actionshift_summary_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto a = make_records("pick_cube", "seen", "oracle", {1}, 3, [](int) { return true; });
  const auto b = make_records("pick_cube", "seen", "no_adapt", {1}, 3, [](int) { return false; });
  {
    std::ofstream f(dir / "a.jsonl");
    for (const auto& r : a) f << to_jsonl_line(r) << "\n";
    std::ofstream g(dir / "b.jsonl");
    for (const auto& r : b) g << to_jsonl_line(r) << "\n";
    g << "{\"partial";
    std::ofstream h(dir / "notes.txt");
    h << "ignored";
  }
  const ResultSet rs = load_results(dir.string());
  EXPECT_EQ(rs.files.size(), 2u);
  EXPECT_EQ(rs.records.size(), 6u);
  ASSERT_EQ(rs.notes.size(), 1u);
  EXPECT_THAT(rs.notes[0], HasSubstr("b.jsonl: ignored an unterminated last line"));
  {
    std::ofstream f(dir / "a.jsonl", std::ios::app);
    f << "not json\n" << to_jsonl_line(a[0]) << "\n";
  }
  EXPECT_THAT([&] { load_results(dir.string()); }, ThrowsMessage<InputError>(HasSubstr("a.jsonl:4: not valid JSON")));
  EXPECT_THAT([&] { load_results((dir / "nope").string()); }, ThrowsMessage<InputError>(HasSubstr("not a results directory")));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace actionshift::eval
