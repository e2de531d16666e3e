#include "actionshift/eval/gates.hpp"

#include "actionshift/core/error.hpp"
#include "record_sets.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <random>

namespace actionshift::eval {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using testing::concat;
using testing::make_records;

const std::vector<std::uint64_t> kSeeds = {20260718, 20260719, 20260720};

// ---- pairing

TEST(PairedRecords, FivePairExampleAndOrderIndependence) {
  const std::vector<bool> c = {true, true, false, true, true}, b = {false, true, false, false, true};
  auto cand = make_records("pick_cube", "seen", "dualabi", {3}, 5, [&](int k) { return c[static_cast<std::size_t>(k)]; });
  auto base = make_records("pick_cube", "seen", "entropy", {3}, 5, [&](int k) { return b[static_cast<std::size_t>(k)]; });
  const auto d = paired_difference(cand, base, 0.95, 2000, 3);
  EXPECT_DOUBLE_EQ(d.estimate, 0.4);
  EXPECT_EQ(d.pairs, 5u);
  std::mt19937 shuffle(1);
  std::shuffle(cand.begin(), cand.end(), shuffle);
  std::shuffle(base.begin(), base.end(), shuffle);
  EXPECT_EQ(paired_difference(cand, base, 0.95, 2000, 3), d);  // pairs are sorted by key first
}

TEST(PairedRecords, MismatchedKeysAreErrors) {
  const auto cand = make_records("pick_cube", "seen", "a", {1}, 6, [](int) { return true; });
  const auto base = make_records("pick_cube", "seen", "b", {1}, 5, [](int) { return true; });
  EXPECT_THAT([&] { paired_difference(cand, base); },
              ThrowsMessage<InputError>(HasSubstr("pairing: episode keys differ: 1 only in candidate, 0 only in baseline "
                                                  "(first (seed 1, contract 1, episode 5))")));
  EXPECT_THAT([&] { paired_difference(concat(cand, cand), cand); },
              ThrowsMessage<InputError>(HasSubstr("duplicate candidate episode (seed 1, contract 0, episode 0)")));
  auto other = cand;
  other[2].contract_sha256 = std::string(64, '0');
  EXPECT_THAT([&] { paired_difference(cand, other); }, ThrowsMessage<InputError>(HasSubstr("ran different contracts")));
  EXPECT_THAT([&] { paired_difference({}, {}); }, ThrowsMessage<InputError>(HasSubstr("no episodes to pair")));
}

TEST(PairedRecords, PromotionErrorsNameTheCellAndTheMethods) {
  // gate promote / gate check with one job unfinished: the message says which cell and which methods
  const auto cand = make_records("push_cube", "seen", "a", {1}, 6, [](int) { return true; });
  const auto base = make_records("push_cube", "seen", "b", {1}, 5, [](int) { return true; });
  EXPECT_THAT([&] { promotion_report(concat(cand, base), "a", "b"); },
              ThrowsMessage<InputError>(HasSubstr("promotion: push_cube/seen: a vs b: episode keys differ: 1 only in candidate")));
}

TEST(Superiority, NeedsThreeDistinctSeeds) {
  EXPECT_FALSE(superiority_allowed({1, 2}));
  EXPECT_FALSE(superiority_allowed({1, 1, 2}));
  EXPECT_TRUE(superiority_allowed({1, 2, 3}));
}

// ---- Gate 0

// ---- Gate 1

std::vector<EpisodeRecord> gate1_records(int n, std::vector<std::uint64_t> seeds = kSeeds) {
  auto r = make_records("pick_cube", "seen", "oracle", seeds, n, [](int) { return true; });
  r = concat(r, make_records("pick_cube", "seen", "no_adapt", seeds, n, [](int) { return false; }));
  r = concat(r, make_records("pick_cube", "unseen_composition", "oracle", seeds, n, [](int k) { return k % 10 != 0; }));
  r = concat(r, make_records("pick_cube", "unseen_composition", "no_adapt", seeds, n, [](int) { return false; }));
  r = concat(r, make_records("pick_cube", "long_lag", "oracle", seeds, n, [](int k) { return k % 3 == 0; }));
  r = concat(r, make_records("pick_cube", "long_lag", "no_adapt", seeds, n, [](int) { return false; }));
  r = concat(r, make_records("pick_cube", "seen", "fixed_probes", seeds, n, [](int) { return true; }));  // ignored
  return r;
}

TEST(Gate1, VerdictsPerCell) {
  const auto report = gate1(gate1_records(40), 2000);
  ASSERT_EQ(report.cells.size(), 3u);
  const auto& lag = report.cells[0];
  const auto& seen = report.cells[1];
  const auto& unseen = report.cells[2];
  EXPECT_EQ(seen.split, "seen");
  EXPECT_EQ(seen.verdict, "pass");
  EXPECT_EQ(seen.oracle->successes, 120);
  EXPECT_EQ(seen.no_adapt->successes, 0);
  EXPECT_DOUBLE_EQ(seen.difference->estimate, 1.0);
  EXPECT_DOUBLE_EQ(seen.difference->lower, 1.0);
  EXPECT_EQ(seen.difference->pairs, 120u);
  EXPECT_TRUE(seen.three_seed_comparison);
  EXPECT_EQ(unseen.verdict, "fail");  // oracle 0.9 < 0.95
  EXPECT_EQ(unseen.reason, "oracle 0.9000 below 0.9500");
  EXPECT_EQ(lag.split, "long_lag");
  EXPECT_EQ(lag.verdict, "descriptive");
  EXPECT_FALSE(report.passed);
  EXPECT_EQ(report.claim_status, "matched_three_seed_ceiling_comparison");
  // the table says why a cell did not pass, on screen (not only in the verdict file)
  const std::string md = gate1_to_markdown(report);
  EXPECT_THAT(md, HasSubstr("- pick_cube/long_lag is descriptive: "));
  EXPECT_THAT(md, HasSubstr("split 'long_lag' is not gated: only seen and unseen_composition are"));
  EXPECT_THAT(md, HasSubstr("- pick_cube/unseen_composition is fail: oracle 0.9000 below 0.9500"));
  EXPECT_EQ(md.find("- pick_cube/seen is"), std::string::npos);
}

TEST(Gate1, PairedEstimateAndClaimStatus) {
  // analogue of a reference-implementation gate test (docs/reference.md, Gates): oracle succeeds on every second episode, no_adapt never: estimate 0.5
  auto r = make_records("push_cube", "seen", "oracle", {1, 2}, 10, [](int k) { return k % 2 == 0; });
  r = concat(r, make_records("push_cube", "seen", "no_adapt", {1, 2}, 10, [](int) { return false; }));
  const auto report = gate1(r, 2000);
  ASSERT_EQ(report.cells.size(), 1u);
  EXPECT_DOUBLE_EQ(report.cells[0].difference->estimate, 0.5);
  EXPECT_FALSE(report.cells[0].three_seed_comparison);
  EXPECT_EQ(report.claim_status, "descriptive_only");
  EXPECT_EQ(report.cells[0].verdict, "fail");
  EXPECT_EQ(report.cells[0].reason, "oracle 0.5000 below 0.9500");
}

TEST(Gate1, AllGatedCellsPassingPassesTheGate) {
  auto r = gate1_records(20);
  r.erase(std::remove_if(r.begin(), r.end(), [](const EpisodeRecord& x) { return x.split == "unseen_composition"; }), r.end());
  const auto report = gate1(r, 1000);
  EXPECT_TRUE(report.passed);
  const auto j = gate1_to_json(report);
  EXPECT_EQ(j["gate"], "gate1");
  EXPECT_EQ(j["cells"]["pick_cube/seen"]["verdict"], "pass");
  EXPECT_EQ(j["cells"]["pick_cube/long_lag"]["verdict"], "descriptive");
  EXPECT_EQ(j["thresholds"]["oracle_min"], 0.95);
  EXPECT_THAT(gate1_to_markdown(report), HasSubstr("| pick_cube | seen | 1.000 ["));
}

TEST(Gate1, MissingMethodIsIncompleteAndMismatchIsAnError) {
  const auto only_oracle = make_records("pick_cube", "seen", "oracle", kSeeds, 5, [](int) { return true; });
  const auto report = gate1(only_oracle, 500);
  EXPECT_EQ(report.cells[0].verdict, "incomplete");
  EXPECT_EQ(report.cells[0].reason, "no no_adapt records");
  EXPECT_FALSE(report.passed);
  const auto short_no_adapt = make_records("pick_cube", "seen", "no_adapt", kSeeds, 4, [](int) { return false; });
  EXPECT_THAT([&] { gate1(concat(only_oracle, short_no_adapt), 500); },
              ThrowsMessage<InputError>(HasSubstr("gate1: pick_cube/seen: oracle vs no_adapt: episode keys differ")));
  const auto other_backbone = make_records("pick_cube", "seen", "no_adapt", kSeeds, 5, [](int) { return false; }, "mlp");
  EXPECT_THAT([&] { gate1(concat(only_oracle, other_backbone), 500); }, ThrowsMessage<InputError>(HasSubstr("mixes backbones")));
}

// ---- promotion

std::vector<EpisodeRecord> with_probes(std::vector<EpisodeRecord> r, int probes) {
  for (auto& x : r) x.probe_steps = probes;
  return r;
}

TEST(Promotion, OneSeedUnderThreeTenthsIsPruned) {
  const auto cand = make_records("pick_cube", "seen", "c", {20260718}, 100, [](int k) { return k % 5 == 0; });
  const auto base = make_records("pick_cube", "seen", "b", {20260718}, 100, [](int) { return false; });
  const auto v = promotion_verdict(cand, base, 1000);
  EXPECT_EQ(v.decision, "prune");
  EXPECT_EQ(v.reason, "one-seed success 0.2000 below 0.3000; a sub-0.3 one-seed result is never promoted");
  const auto good = make_records("pick_cube", "seen", "c", {20260718}, 100, [](int k) { return k % 2 == 0; });
  EXPECT_EQ(promotion_verdict(good, base, 1000).decision, "extend_seeds");
}

TEST(Promotion, FivePointsOverBaselineOnThreeSeeds) {
  const auto cand = make_records("pick_cube", "seen", "c", kSeeds, 200, [](int k) { return k % 10 < 8; });
  const auto base = make_records("pick_cube", "seen", "b", kSeeds, 200, [](int k) { return k % 10 < 6; });
  const auto v = promotion_verdict(cand, base, 2000);
  EXPECT_EQ(v.decision, "promote");
  EXPECT_TRUE(v.five_point_rule);
  EXPECT_NEAR(v.difference.estimate, 0.2, 1e-12);
  const auto close = make_records("pick_cube", "seen", "c", kSeeds, 200, [](int k) { return k % 50 < 31; });
  const auto base2 = make_records("pick_cube", "seen", "b", kSeeds, 200, [](int k) { return k % 50 < 30; });
  const auto r = promotion_verdict(close, base2, 2000);
  EXPECT_EQ(r.decision, "reject");
  EXPECT_FALSE(r.five_point_rule);
  EXPECT_THAT(r.reason, HasSubstr("below 0.0500 and no Pareto improvement"));
}

TEST(Promotion, ParetoPointOnProbeCost) {
  const auto cand = with_probes(make_records("pick_cube", "seen", "c", kSeeds, 100, [](int k) { return k % 4 != 0; }), 2);
  const auto base = with_probes(make_records("pick_cube", "seen", "b", kSeeds, 100, [](int k) { return k % 4 != 0; }), 6);
  const auto v = promotion_verdict(cand, base, 1000);
  EXPECT_EQ(v.decision, "promote");
  EXPECT_FALSE(v.five_point_rule);
  EXPECT_TRUE(v.pareto_rule);
  EXPECT_THAT(v.reason, HasSubstr("Pareto point: probe steps 2.00 vs 6.00"));
  // same success at a higher cost is not a Pareto point
  EXPECT_EQ(promotion_verdict(base, cand, 1000).decision, "reject");
}

TEST(Promotion, ACheaperTieAtTheFloorPromotesNothing) {
  // 0.000 vs 0.000 with fewer probe steps: cheaper, "not less successful", and meaningless
  const auto cand = with_probes(make_records("pick_cube", "long_lag", "c", kSeeds, 100, [](int) { return false; }), 1);
  const auto base = with_probes(make_records("pick_cube", "long_lag", "b", kSeeds, 100, [](int) { return false; }), 6);
  const auto v = promotion_verdict(cand, base, 1000);
  EXPECT_FALSE(v.pareto_rule);
  EXPECT_EQ(v.decision, "reject");
  EXPECT_THAT(v.reason, HasSubstr("below the Pareto floor 0.3000"));
  // the same tie just above the floor is a Pareto point
  const auto cand2 = with_probes(make_records("pick_cube", "long_lag", "c", kSeeds, 100, [](int k) { return k % 10 < 3; }), 1);
  const auto base2 = with_probes(make_records("pick_cube", "long_lag", "b", kSeeds, 100, [](int k) { return k % 10 < 3; }), 6);
  EXPECT_EQ(promotion_verdict(cand2, base2, 1000).decision, "promote");
  // and just below it is not
  const auto cand3 = with_probes(make_records("pick_cube", "long_lag", "c", kSeeds, 100, [](int k) { return k % 10 < 2; }), 1);
  const auto base3 = with_probes(make_records("pick_cube", "long_lag", "b", kSeeds, 100, [](int k) { return k % 10 < 2; }), 6);
  EXPECT_EQ(promotion_verdict(cand3, base3, 1000).decision, "reject");
}

TEST(Promotion, ReportCellsStateTheirEpisodes) {
  const auto cand = with_probes(make_records("pick_cube", "seen", "c", kSeeds, 40, [](int k) { return k % 4 != 0; }), 2);
  const auto base = with_probes(make_records("pick_cube", "seen", "b", kSeeds, 40, [](int k) { return k % 4 != 0; }), 6);
  auto all = cand;
  all.insert(all.end(), base.begin(), base.end());
  const auto j = promotion_report(all, "c", "b", 500);
  EXPECT_EQ(j["cells"]["pick_cube/seen"]["episodes"], 120);
  EXPECT_EQ(j["rules"]["pareto_success_floor"], 0.3);
}

TEST(VerdictFiles, AVerdictOnFewerEpisodesThanExpectedIsARegression) {
  const nlohmann::json expected = {{"gate", "promotion"},
                                   {"cells",
                                    {{"a/seen", {{"verdict", "promote"}, {"episodes", 600}}},
                                     {"b/seen", {{"verdict", "reject"}, {"episodes", 600}}},
                                     {"c/seen", {{"verdict", "promote"}, {"episodes", 600}}}}}};
  const nlohmann::json actual = {{"gate", "promotion"},
                                 {"cells",
                                  {{"a/seen", {{"verdict", "promote"}, {"episodes", 60}}},
                                   {"b/seen", {{"verdict", "reject"}, {"episodes", 60}}},
                                   {"c/seen", {{"verdict", "promote"}, {"episodes", 600}}}}}};
  const auto changes = compare_verdicts(expected, actual);
  ASSERT_EQ(changes.size(), 3u);
  EXPECT_TRUE(changes[0].regression);
  EXPECT_THAT(changes[0].line, HasSubstr("rests on 60 episodes, fewer than the expected verdict's 600"));
  EXPECT_TRUE(changes[1].regression);  // even a negative verdict cannot be checked on fewer episodes
  EXPECT_FALSE(changes[2].regression);
  // gate 1 cells count the smaller of their two Wilson totals
  const nlohmann::json e1 = {{"gate", "gate1"},
                             {"cells", {{"a/seen", {{"verdict", "pass"}, {"oracle", {{"total", 512}}}, {"no_adapt", {{"total", 512}}}}}}}};
  const nlohmann::json a1 = {{"gate", "gate1"},
                             {"cells", {{"a/seen", {{"verdict", "pass"}, {"oracle", {{"total", 512}}}, {"no_adapt", {{"total", 16}}}}}}}};
  EXPECT_TRUE(compare_verdicts(e1, a1)[0].regression);
  EXPECT_FALSE(compare_verdicts(e1, e1)[0].regression);
}

TEST(Promotion, SafetyRegressionBlocksPromotion) {
  auto cand = make_records("pick_cube", "seen", "c", kSeeds, 100, [](int k) { return k % 10 < 9; });
  const auto base = make_records("pick_cube", "seen", "b", kSeeds, 100, [](int k) { return k % 10 < 5; });
  for (std::size_t i = 0; i < cand.size(); i += 20) cand[i].safety_flags = {"workspace_violation"};
  const auto v = promotion_verdict(cand, base, 1000);
  EXPECT_TRUE(v.five_point_rule);
  EXPECT_TRUE(v.safety_regression);
  EXPECT_EQ(v.decision, "reject");
  EXPECT_EQ(v.reason, "safety regression: flagged-episode rate 0.0500 vs baseline 0.0000");
}

// ---- verdict comparison

TEST(VerdictFiles, RegressionIsAnExpectedPassNoLongerPassing) {
  const nlohmann::json expected = {{"gate", "gate1"},
                                   {"cells",
                                    {{"a/seen", {{"verdict", "pass"}}},
                                     {"b/seen", {{"verdict", "pass"}}},
                                     {"c/seen", {{"verdict", "fail"}}},
                                     {"d/seen", {{"verdict", "pass"}}}}}};
  const nlohmann::json actual = {{"gate", "gate1"},
                                 {"cells",
                                  {{"a/seen", {{"verdict", "pass"}}},
                                   {"b/seen", {{"verdict", "fail"}, {"reason", "oracle 0.9000 below 0.9500"}}},
                                   {"c/seen", {{"verdict", "pass"}}},
                                   {"e/seen", {{"verdict", "pass"}}}}}};
  const auto changes = compare_verdicts(expected, actual);
  ASSERT_EQ(changes.size(), 5u);
  EXPECT_FALSE(changes[0].regression);
  EXPECT_TRUE(changes[1].regression);
  EXPECT_EQ(changes[1].line, "REGRESSION b/seen: expected pass, got fail (oracle 0.9000 below 0.9500)");
  EXPECT_FALSE(changes[2].regression);
  EXPECT_THAT(changes[2].line, HasSubstr("improved"));
  EXPECT_TRUE(changes[3].regression);
  EXPECT_EQ(changes[3].actual, "missing");
  EXPECT_THAT(changes[4].line, HasSubstr("new e/seen"));
  nlohmann::json other = actual;
  other["gate"] = "gate0";
  EXPECT_THAT([&] { compare_verdicts(expected, other, "exp.json"); }, ThrowsMessage<InputError>(HasSubstr("exp.json: gate")));
  EXPECT_THAT([&] { compare_verdicts(nlohmann::json::object(), actual, "exp.json"); },
              ThrowsMessage<InputError>(HasSubstr("not a verdict file")));
}

}  // namespace
}  // namespace actionshift::eval
