#include "actionshift/eval/compare.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/data/paper_numbers.hpp"
#include "actionshift/eval/gates.hpp"
#include "actionshift/eval/summary.hpp"
#include "record_sets.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

namespace actionshift::eval {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using testing::concat;
using testing::make_records;

const std::vector<std::uint64_t> kSeeds = {20260718, 20260719, 20260720};

// a small paper-numbers file: one cell and one difference per significance state
json paper_doc() {
  const json seeds = kSeeds;
  return {{"schema_version", "1.0"},
          {"entries",
           {{{"id", "t5.entropy"}, {"kind", "cell"}, {"quantity", "success_once"}, {"task", "pick_cube"}, {"split", "reference_seen"},
             {"method", "entropy_probes"}, {"value", 0.987}, {"interval", {0.974, 0.993}}, {"seeds", seeds}, {"episodes", 600},
             {"source", "Table 5"}},
            {{"id", "t5.entropy.probe"}, {"kind", "cell"}, {"quantity", "mean_probe_steps"}, {"task", "pick_cube"},
             {"split", "reference_seen"}, {"method", "entropy_probes"}, {"value", 6.0}, {"seeds", seeds}, {"episodes", 600},
             {"source", "Table 5"}},
            {{"id", "t4.entropy.delay"}, {"kind", "cell"}, {"quantity", "success_once"}, {"task", "pick_cube"},
             {"split", "reference_seen"}, {"method", "entropy_probes"}, {"backbones", {"expert-delay-aware"}}, {"value", 0.5},
             {"seeds", seeds}, {"episodes", 600}, {"source", "Table 4"}},
            {{"id", "d.sig"}, {"kind", "difference"}, {"quantity", "success_difference"}, {"task", "pick_cube"},
             {"split", "reference_seen"}, {"candidate", "entropy_probes"}, {"baseline", "fixed_probes"}, {"value", 0.058},
             {"interval", {0.037, 0.082}}, {"significant", true}, {"seeds", seeds}, {"episodes", 600}, {"source", "§5.2"}},
            {{"id", "d.ns"}, {"kind", "difference"}, {"quantity", "success_difference"}, {"task", "pick_cube"},
             {"split", "reference_seen"}, {"candidate", "dualabi"}, {"baseline", "entropy_probes"}, {"value", -0.003},
             {"interval", {-0.017, 0.010}}, {"significant", false}, {"seeds", seeds}, {"episodes", 600}, {"source", "§5.5"}},
            {{"id", "d.unknown"}, {"kind", "difference"}, {"quantity", "success_difference"}, {"task", "pick_cube"},
             {"split", "reference_seen"}, {"candidate", "entropy_probes"}, {"baseline", "exact_belief"}, {"value", 0.058},
             {"significant", nullptr}, {"note", "no interval given"}, {"seeds", seeds}, {"episodes", 600},
             {"source", "reference implementation, tournament"}}}}};
}

PaperNumbers paper() { return parse_paper_numbers(paper_doc().dump(), "paper.json"); }

std::vector<EpisodeRecord> cell(const std::string& method, int n, const std::function<bool(int)>& success,
                                const std::vector<std::uint64_t>& seeds = kSeeds, const std::string& backbone = "expert") {
  return make_records("pick_cube", "reference_seen", method, seeds, n, success, backbone);
}

const json& find_cell(const json& j, const std::string& method, const std::string& backbone = "expert") {
  for (const auto& c : j["cells"])
    if (c["method"] == method && c["backbone"] == backbone) return c;
  throw std::runtime_error("no cell " + method);
}

// ---- cells

TEST(Compare, CellCarriesWilsonPerSeedProbeCostAndSafetyRates) {
  auto recs = cell("fixed_probes", 10, [](int k) { return k < 7; }, {1, 2});
  for (std::size_t i = 0; i < recs.size(); ++i) {
    recs[i].probe_steps = static_cast<std::int64_t>(i % 4);
    recs[i].probe_displacement = 0.01 * static_cast<double>(i % 2);
  }
  recs[0].safety_flags = {"workspace"};
  recs[1].safety_flags = {"workspace", "collision"};
  recs[12].success_once = false;  // seed 2: 6 of 10
  const json j = compare_records(recs, {}, paper());
  ASSERT_EQ(j["cells"].size(), 1u);
  const json& c = j["cells"][0];
  const WilsonInterval w = wilson_interval(13, 20);
  EXPECT_EQ(c["episodes"], 20);
  EXPECT_EQ(c["success_once"]["successes"], 13);
  EXPECT_DOUBLE_EQ(c["success_once"]["rate"].get<double>(), 0.65);
  EXPECT_DOUBLE_EQ(c["success_once"]["lower"].get<double>(), w.lower);
  EXPECT_DOUBLE_EQ(c["success_once"]["upper"].get<double>(), w.upper);
  EXPECT_NEAR(w.lower, 0.4329, 5e-4);  // Wilson 95 % of 13/20, as printed by any statistics package
  EXPECT_NEAR(w.upper, 0.8188, 5e-4);
  ASSERT_EQ(c["per_seed"].size(), 2u);
  EXPECT_EQ(c["per_seed"][0], json({{"seed", 1}, {"episodes", 10}, {"successes", 7}, {"rate", 0.7}}));
  EXPECT_EQ(c["per_seed"][1]["successes"], 6);
  EXPECT_DOUBLE_EQ(c["mean_probe_steps"].get<double>(), (0 + 1 + 2 + 3) * 5 / 20.0);
  EXPECT_DOUBLE_EQ(c["mean_probe_displacement"].get<double>(), 0.005);
  EXPECT_EQ(c["safety"]["episodes_with_flags"], 2);
  EXPECT_DOUBLE_EQ(c["safety"]["rate"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(c["safety"]["flags"]["workspace"]["rate"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(c["safety"]["flags"]["collision"]["rate"].get<double>(), 0.05);
  EXPECT_EQ(c["paper"], json::object());  // the small paper file has no fixed_probes cell
  EXPECT_EQ(j["schema_version"], "1.0");
  EXPECT_EQ(j["bootstrap"]["samples"], kBootstrapSamples);
  EXPECT_EQ(j["bootstrap"]["seed"], kBootstrapSeed);
}

TEST(Compare, VariantLabelIsItsOwnCellAndGetsNoPaperNumber) {
  const auto plain = cell("entropy_probes", 10, [](int k) { return k != 3; });
  const auto variant = cell("entropy_probes{calibrated}", 10, [](int k) { return k % 2 == 0; });
  const json j = compare_records(concat(plain, variant), {{"entropy_probes{calibrated}", "entropy_probes"}}, paper());
  ASSERT_EQ(j["cells"].size(), 2u);
  const json& p = find_cell(j, "entropy_probes");
  const json& v = find_cell(j, "entropy_probes{calibrated}");
  EXPECT_EQ(p["episodes"], 30);
  EXPECT_EQ(v["episodes"], 30);
  EXPECT_EQ(v["success_once"]["successes"], 15);
  EXPECT_EQ(v["method_base"], "entropy_probes");
  EXPECT_EQ(p["paper"]["success_once"]["id"], "t5.entropy");
  EXPECT_EQ(p["paper"]["mean_probe_steps"]["value"], 6.0);
  EXPECT_EQ(v["paper"], json::object());
  ASSERT_EQ(j["comparisons"].size(), 1u);
  const json& cmp = j["comparisons"][0];
  EXPECT_TRUE(cmp["paper"].is_null());
  EXPECT_TRUE(cmp["sign_agreement"].is_null());
  EXPECT_THAT(cmp["sign_agreement_reason"].get<std::string>(), HasSubstr("{...} suffix"));
}

TEST(Compare, BackboneSpecificPaperNumberWinsOverTheGeneralOne) {
  const auto a = cell("entropy_probes", 4, [](int) { return true; }, kSeeds, "expert");
  const auto b = cell("entropy_probes", 4, [](int) { return true; }, kSeeds, "expert-delay-aware");
  const json j = compare_records(concat(a, b), {}, paper());
  EXPECT_EQ(find_cell(j, "entropy_probes", "expert")["paper"]["success_once"]["id"], "t5.entropy");
  EXPECT_EQ(find_cell(j, "entropy_probes", "expert-delay-aware")["paper"]["success_once"]["id"], "t4.entropy.delay");
}

TEST(Compare, CellsCarryPerContractCountsAndWilsonIntervals) {
  // 2 contracts (index k % 2), 10 episodes per seed over 3 seeds: contract 0 succeeds at k = 0, 2, 4 (3 of 5
  // per seed), contract 1 at every odd k (5 of 5)
  const auto recs = cell("oracle", 10, [](int k) { return k % 2 == 1 || k < 6; });
  const json j = compare_records(recs, {}, paper());
  const json& pc = find_cell(j, "oracle")["per_contract"];
  ASSERT_EQ(pc.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const std::int64_t k = i == 0 ? 9 : 15;
    EXPECT_EQ(pc[i]["contract_index"], i);
    EXPECT_EQ(pc[i]["contract_sha256"], recs[static_cast<std::size_t>(i)].contract_sha256);
    EXPECT_EQ(pc[i]["episodes"], 15);
    EXPECT_EQ(pc[i]["successes"], k);
    EXPECT_EQ(pc[i]["success_once"], wilson_json(wilson_interval(k, 15)));
    EXPECT_EQ(pc[i].size(), 5u);
  }
  EXPECT_NEAR(pc[0]["success_once"]["lower"].get<double>(), 0.3575, 5e-4);  // Wilson 95 % of 9/15
  EXPECT_NEAR(pc[0]["success_once"]["upper"].get<double>(), 0.8018, 5e-4);
  // one contract index with two hashes in a cell: an error naming the cell
  auto bad = recs;
  bad[2].contract_sha256 = std::string(64, 'b');
  EXPECT_THAT([&] { compare_records(bad, {}, paper()); },
              ThrowsMessage<InputError>(HasSubstr("pick_cube/reference_seen/oracle/expert: contract index 0 carries two contract hashes")));
}

// ---- pairs

TEST(Compare, CrossBackbonePairIsThePairedDifferenceOnTheSameEpisodes) {
  std::mt19937 rng(11);
  std::bernoulli_distribution pc(0.6), pb(0.2);
  const auto delay = cell("exact_belief", 40, [&](int) { return pc(rng); }, kSeeds, "ppo-delay-aware");
  const auto reactive = cell("exact_belief", 40, [&](int) { return pb(rng); }, kSeeds, "ppo");
  const auto other = cell("oracle", 40, [](int) { return true; }, kSeeds, "ppo");  // not part of the pair
  std::map<PairKey, std::pair<bool, bool>> by_key;
  for (const auto& r : delay) by_key[{r.seed, r.contract_index, r.episode_index}].first = r.success_once;
  for (const auto& r : reactive) by_key[{r.seed, r.contract_index, r.episode_index}].second = r.success_once;
  std::vector<bool> c, b;
  for (const auto& [k, v] : by_key) {
    c.push_back(v.first);
    b.push_back(v.second);
  }
  const BootstrapInterval expected = paired_success_difference(c, b, 0.95, kBootstrapSamples, kBootstrapSeed);
  const auto pair = parse_comparison_pair("exact_belief@ppo-delay-aware vs exact_belief@ppo", "--pair", "");
  const json j = compare_records(concat(concat(reactive, other), delay), {pair}, paper());
  ASSERT_EQ(j["comparisons"].size(), 1u);
  const json& d = j["comparisons"][0];
  EXPECT_EQ(d["candidate"], "exact_belief");
  EXPECT_EQ(d["baseline"], "exact_belief");
  EXPECT_EQ(d["candidate_backbone"], "ppo-delay-aware");
  EXPECT_EQ(d["baseline_backbone"], "ppo");
  EXPECT_TRUE(d["backbone"].is_null());
  EXPECT_EQ(d["pairs"], 120);
  EXPECT_EQ(d["seeds"], 3);
  EXPECT_DOUBLE_EQ(d["difference"]["estimate"].get<double>(), expected.estimate);
  EXPECT_DOUBLE_EQ(d["difference"]["lower"].get<double>(), expected.lower);
  EXPECT_DOUBLE_EQ(d["difference"]["upper"].get<double>(), expected.upper);
  EXPECT_TRUE(d["paper"].is_null());
  EXPECT_THAT(d["sign_agreement_reason"].get<std::string>(), HasSubstr("between these two backbones"));
  EXPECT_EQ(d["promotion"]["verdict"], promotion_verdict(delay, reactive).decision);
  ASSERT_EQ(j["pairs"].size(), 1u);
  EXPECT_EQ(j["pairs"][0]["candidate_backbone"], "ppo-delay-aware");
  EXPECT_EQ(j["pairs"][0]["baseline_backbone"], "ppo");
  EXPECT_EQ(j["pairs"][0]["cells_compared"], 1);
  // a same-backbone pair names no backbones in its pair entry and its backbone in each comparison
  const json k = compare_records(concat(reactive, other), {{"oracle", "exact_belief"}}, paper());
  EXPECT_TRUE(k["pairs"][0]["candidate_backbone"].is_null());
  EXPECT_EQ(k["comparisons"][0]["backbone"], "ppo");
  EXPECT_EQ(k["comparisons"][0]["candidate_backbone"], "ppo");
  EXPECT_EQ(k["comparisons"][0]["baseline_backbone"], "ppo");
}

TEST(Compare, CrossBackbonePairOverDifferentEpisodesIsAnErrorNamingBothCells) {
  const auto delay = cell("exact_belief", 10, [](int) { return true; }, kSeeds, "ppo-delay-aware");
  const auto reactive = cell("exact_belief", 9, [](int) { return false; }, kSeeds, "ppo");
  const auto pair = parse_comparison_pair("exact_belief@ppo-delay-aware vs exact_belief@ppo", "--pair", "");
  EXPECT_THAT([&] { compare_records(concat(delay, reactive), {pair}, paper()); },
              ThrowsMessage<InputError>(HasSubstr("pick_cube/reference_seen: exact_belief@ppo-delay-aware vs exact_belief@ppo: the two "
                                                  "cells hold different episodes: 3 only in exact_belief@ppo-delay-aware, 0 only in "
                                                  "exact_belief@ppo")));
  // no (task, split) holds both cells: an error listing the cells present
  EXPECT_THAT([&] { compare_records(delay, {pair}, paper()); },
              ThrowsMessage<InputError>(HasSubstr("pair 'exact_belief@ppo-delay-aware vs exact_belief@ppo': no (task, split) holds "
                                                  "both cells (cells in the results: exact_belief@ppo-delay-aware)")));
  const json j = compare_records(concat(delay, cell("exact_belief", 10, [](int) { return true; }, kSeeds, "ppo")), {pair}, paper());
  EXPECT_EQ(j["comparisons"][0]["difference"]["estimate"], 0.0);
}

TEST(Compare, PairedDifferenceIsTheLibrarysOnTheKeySortedPairs) {
  std::mt19937 rng(7);
  std::bernoulli_distribution pc(0.8), pb(0.5);
  auto cand = cell("entropy_probes", 40, [&](int) { return pc(rng); });
  auto base = cell("fixed_probes", 40, [&](int) { return pb(rng); });
  // expected: the pairs in PairKey order through eval::paired_success_difference
  std::map<PairKey, std::pair<bool, bool>> by_key;
  for (const auto& r : cand) by_key[{r.seed, r.contract_index, r.episode_index}].first = r.success_once;
  for (const auto& r : base) by_key[{r.seed, r.contract_index, r.episode_index}].second = r.success_once;
  std::vector<bool> c, b;
  std::map<std::uint64_t, std::pair<int, int>> seed_diff;  // seed → (cand − base successes, pairs)
  for (const auto& [k, v] : by_key) {
    c.push_back(v.first);
    b.push_back(v.second);
    seed_diff[k.seed].first += static_cast<int>(v.first) - static_cast<int>(v.second);
    ++seed_diff[k.seed].second;
  }
  const BootstrapInterval expected = paired_success_difference(c, b, 0.95, kBootstrapSamples, kBootstrapSeed);
  std::shuffle(cand.begin(), cand.end(), rng);
  std::shuffle(base.begin(), base.end(), rng);
  const json j = compare_records(concat(base, cand), {{"entropy_probes", "fixed_probes"}}, paper());
  ASSERT_EQ(j["comparisons"].size(), 1u);
  const json& d = j["comparisons"][0];
  EXPECT_EQ(d["pairs"], 120);
  EXPECT_EQ(d["seeds"], 3);
  EXPECT_DOUBLE_EQ(d["difference"]["estimate"].get<double>(), expected.estimate);
  EXPECT_DOUBLE_EQ(d["difference"]["lower"].get<double>(), expected.lower);
  EXPECT_DOUBLE_EQ(d["difference"]["upper"].get<double>(), expected.upper);
  EXPECT_EQ(d["difference"]["samples"], kBootstrapSamples);
  ASSERT_EQ(d["per_seed"].size(), 3u);
  for (const auto& s : d["per_seed"]) {
    const auto& [diff, n] = seed_diff.at(s["seed"].get<std::uint64_t>());
    EXPECT_EQ(s["pairs"], n);
    EXPECT_DOUBLE_EQ(s["difference"].get<double>(), static_cast<double>(diff) / n);
  }
  // the promotion verdict is gates.cpp's, on the same records
  const PromotionVerdict v = promotion_verdict(cand, base);
  EXPECT_EQ(d["promotion"]["verdict"], v.decision);
  EXPECT_EQ(d["promotion"]["reason"], v.reason);
  EXPECT_DOUBLE_EQ(v.difference.estimate, expected.estimate);
}

TEST(Compare, CellsThatDoNotPairExactlyAreAnErrorNamingTheCell) {
  const auto cand = cell("entropy_probes", 10, [](int) { return true; });
  const auto base = cell("fixed_probes", 9, [](int) { return true; });
  EXPECT_THAT([&] { compare_records(concat(cand, base), {{"entropy_probes", "fixed_probes"}}, paper()); },
              ThrowsMessage<InputError>(HasSubstr("pick_cube/reference_seen/expert: entropy_probes vs fixed_probes: the two cells hold "
                                                  "different episodes: 3 only in entropy_probes, 0 only in fixed_probes")));
  auto other = cell("fixed_probes", 10, [](int) { return true; });
  for (auto& r : other)  // a consistent cell whose contract 0 is another contract than the candidate's
    if (r.contract_index == 0) r.contract_sha256 = std::string(64, 'a');
  EXPECT_THAT([&] { compare_records(concat(cand, other), {{"entropy_probes", "fixed_probes"}}, paper()); },
              ThrowsMessage<InputError>(HasSubstr("ran different contracts")));
  // a pair that no cell holds is an error naming the labels present, not an empty result
  EXPECT_THAT([&] { compare_records(cand, {{"entropy_probes", "fixed_probe"}}, paper()); },
              ThrowsMessage<InputError>(HasSubstr("pair 'entropy_probes vs fixed_probe': no (task, split, backbone) holds both labels "
                                                  "(labels in the results: entropy_probes)")));
}

TEST(Compare, SignAgreementOnlyWhereThePaperAndWeAreBothSignificant) {
  const auto entropy = cell("entropy_probes", 40, [](int k) { return k % 10 != 0; });  // 0.9
  const auto fixed = cell("fixed_probes", 40, [](int k) { return k % 2 == 0; });       // 0.5
  const auto dual = cell("dualabi", 40, [](int k) { return k % 10 != 1; });            // 0.9
  const auto exact = cell("exact_belief", 40, [](int k) { return k % 10 < 3; });        // 0.3
  const json j = compare_records(concat(concat(entropy, fixed), concat(dual, exact)),
                                 {{"entropy_probes", "fixed_probes"}, {"fixed_probes", "entropy_probes"},
                                  {"dualabi", "entropy_probes"}, {"entropy_probes", "exact_belief"}},
                                 paper());
  ASSERT_EQ(j["comparisons"].size(), 4u);
  const json& same = j["comparisons"][0];
  EXPECT_TRUE(same["difference"]["excludes_zero"].get<bool>());
  EXPECT_EQ(same["sign_agreement"], "same");
  EXPECT_TRUE(same["sign_agreement_reason"].is_null());
  EXPECT_EQ(same["paper"]["entry"]["id"], "d.sig");
  // the same paper entry read backwards: negated, and our negative difference agrees with it
  const json& rev = j["comparisons"][1];
  EXPECT_TRUE(rev["paper"]["reversed"].get<bool>());
  EXPECT_DOUBLE_EQ(rev["paper"]["value"].get<double>(), -0.058);
  EXPECT_EQ(rev["paper"]["interval"], json({-0.082, -0.037}));
  EXPECT_EQ(rev["sign_agreement"], "same");
  // the paper's difference is not significant: null with the reason, whatever ours is
  const json& ns = j["comparisons"][2];
  EXPECT_EQ(ns["paper"]["significant"], false);
  EXPECT_TRUE(ns["sign_agreement"].is_null());
  EXPECT_THAT(ns["sign_agreement_reason"].get<std::string>(), HasSubstr("the paper's difference is not significant"));
  // no interval in the paper: significance unknown, null with its note
  const json& unknown = j["comparisons"][3];
  EXPECT_TRUE(unknown["difference"]["excludes_zero"].get<bool>());
  EXPECT_TRUE(unknown["paper"]["significant"].is_null());
  EXPECT_TRUE(unknown["sign_agreement"].is_null());
  EXPECT_THAT(unknown["sign_agreement_reason"].get<std::string>(), HasSubstr("no interval given"));
}

TEST(Compare, SignAgreementSaysDifferentAndNullWhenOurIntervalIncludesZero) {
  // ours: entropy below fixed, significantly; the paper's: above
  const auto entropy = cell("entropy_probes", 40, [](int k) { return k % 2 == 0; });
  const auto fixed = cell("fixed_probes", 40, [](int k) { return k % 10 != 0; });
  json j = compare_records(concat(entropy, fixed), {{"entropy_probes", "fixed_probes"}}, paper());
  EXPECT_EQ(j["comparisons"][0]["sign_agreement"], "different");
  const auto tie = cell("fixed_probes", 40, [](int k) { return k % 2 == 1; });
  j = compare_records(concat(entropy, tie), {{"entropy_probes", "fixed_probes"}}, paper());
  EXPECT_TRUE(j["comparisons"][0]["sign_agreement"].is_null());
  EXPECT_THAT(j["comparisons"][0]["sign_agreement_reason"].get<std::string>(), HasSubstr("includes 0"));
}

TEST(Compare, RejectionsCarryTheirRuleAndReason) {
  // three seeds, same success, the candidate flags a fifth of its episodes: a safety regression
  auto cand = cell("entropy_probes", 20, [](int) { return true; });
  const auto base = cell("fixed_probes", 20, [](int) { return true; });
  for (std::size_t i = 0; i < cand.size(); i += 5) cand[i].safety_flags = {"workspace"};
  json j = compare_records(concat(cand, base), {{"entropy_probes", "fixed_probes"}}, paper());
  const json& p = j["comparisons"][0]["promotion"];
  EXPECT_EQ(p["verdict"], "reject");
  EXPECT_EQ(p["rule"], "safety_regression");
  EXPECT_THAT(p["reason"].get<std::string>(), HasSubstr("safety regression: flagged-episode rate 0.2000 vs baseline 0.0000"));
  // three seeds, equal success and cost: no five-point gain, no Pareto point
  j = compare_records(concat(cell("dualabi", 20, [](int k) { return k % 2 == 0; }), cell("exact_belief", 20, [](int k) { return k % 2 == 0; })),
                      {{"dualabi", "exact_belief"}}, paper());
  EXPECT_EQ(j["comparisons"][0]["promotion"]["verdict"], "reject");
  EXPECT_EQ(j["comparisons"][0]["promotion"]["rule"], "no_five_point_gain_or_pareto_point");
  EXPECT_THAT(j["comparisons"][0]["promotion"]["reason"].get<std::string>(), HasSubstr("below 0.0500"));
  // one seed under 0.3: pruned
  j = compare_records(concat(cell("dualabi", 20, [](int k) { return k < 4; }, {5}), cell("exact_belief", 20, [](int) { return false; }, {5})),
                      {{"dualabi", "exact_belief"}}, paper());
  EXPECT_EQ(j["comparisons"][0]["promotion"]["verdict"], "prune");
  EXPECT_EQ(j["comparisons"][0]["promotion"]["rule"], "one_seed_below_prune_floor");
  EXPECT_THAT(j["comparisons"][0]["promotion"]["reason"].get<std::string>(), HasSubstr("one-seed success 0.2000 below 0.3000"));
}

TEST(Compare, PairsListTheCellsWithOneSide) {
  const auto a = make_records("pick_cube", "reference_seen", "dualabi", kSeeds, 4, [](int) { return true; });
  const auto b = make_records("pick_cube", "reference_seen", "exact_belief", kSeeds, 4, [](int) { return true; });
  const auto c = make_records("push_cube", "reference_seen", "dualabi", kSeeds, 4, [](int) { return true; });
  const json j = compare_records(concat(concat(a, b), c), {{"dualabi", "exact_belief"}}, paper());
  ASSERT_EQ(j["pairs"].size(), 1u);
  EXPECT_EQ(j["pairs"][0]["cells_compared"], 1);
  EXPECT_EQ(j["pairs"][0]["cells_with_one_side"],
            json::array({{{"task", "push_cube"}, {"split", "reference_seen"}, {"backbone", "expert"}, {"present", "dualabi"}}}));
}

TEST(ComparePairs, LabelsWithBracesCommasAndEqualsSurvive) {
  const auto p = parse_comparison_pair("grammar_belief{hold=2,corrector=on} vs grammar_belief", "--pair", "");
  EXPECT_EQ(p.candidate, "grammar_belief{hold=2,corrector=on}");
  EXPECT_EQ(p.baseline, "grammar_belief");
  EXPECT_EQ(method_base_name(p.candidate), "grammar_belief");
  EXPECT_THROW(parse_comparison_pair("a,b", "--pair", ""), InputError);
  EXPECT_THROW(parse_comparison_pair("a vs a", "--pair", ""), InputError);
  EXPECT_THROW(parse_comparison_pair(" vs b", "--pair", ""), InputError);
  EXPECT_THROW(parse_comparison_pair("a vs b vs c", "--pair", ""), InputError);
  const auto list = parse_pairs_text("# header\n\nentropy_probes vs fixed_probes\n  dualabi vs entropy_probes  \n", "pairs.txt");
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[1], (ComparisonPair{"dualabi", "entropy_probes"}));
  EXPECT_THAT([] { parse_pairs_text("a vs b\nnonsense\n", "pairs.txt"); },
              ThrowsMessage<InputError>(HasSubstr("pairs.txt:2: pair: expected 'CANDIDATE vs BASELINE'")));
  EXPECT_THAT([] { compare_records(make_records("t", "s", "a", {1}, 2, [](int) { return true; }), {{"a", "b"}, {"a", "b"}}, PaperNumbers{}); },
              ThrowsMessage<InputError>(HasSubstr("given twice")));
}

TEST(ComparePairs, ASideMayNameABackboneAfterTheLabel) {
  auto p = parse_comparison_pair("exact_belief@ppo-delay-aware vs exact_belief@ppo", "--pair", "");
  EXPECT_EQ(p, (ComparisonPair{"exact_belief", "exact_belief", "ppo-delay-aware", "ppo"}));
  EXPECT_TRUE(p.cross_backbone());
  EXPECT_EQ(p.text(), "exact_belief@ppo-delay-aware vs exact_belief@ppo");
  // an '@' inside the braces belongs to the label; the first '@' after them separates; a backbone may hold '@'
  p = parse_comparison_pair("m{note=a@b} vs m", "--pair", "");
  EXPECT_EQ(p, (ComparisonPair{"m{note=a@b}", "m"}));
  EXPECT_FALSE(p.cross_backbone());
  p = parse_comparison_pair("m{note=a@b}@mlp:/w/a@b.asmlp vs m@expert", "--pair", "");
  EXPECT_EQ(p, (ComparisonPair{"m{note=a@b}", "m", "mlp:/w/a@b.asmlp", "expert"}));
  EXPECT_THAT([] { parse_comparison_pair("a@x vs b", "--pair", ""); },
              ThrowsMessage<InputError>(HasSubstr("name a backbone on both sides")));
  EXPECT_THAT([] { parse_comparison_pair("a@x vs a@x", "--pair", ""); }, ThrowsMessage<InputError>(HasSubstr("the same cell")));
  EXPECT_THROW(parse_comparison_pair("a@ vs a@x", "--pair", ""), InputError);
  EXPECT_THROW(parse_comparison_pair("@x vs a@y", "--pair", ""), InputError);
  EXPECT_NO_THROW(parse_comparison_pair("a@x vs b@x", "--pair", ""));
  EXPECT_THAT([] { compare_records(make_records("t", "s", "a", {1}, 2, [](int) { return true; }), {{"a", "a", "x", "y"}, {"a", "a", "x", "y"}}, PaperNumbers{}); },
              ThrowsMessage<InputError>(HasSubstr("pair 'a@x vs a@y': given twice")));
}

// ---- the paper-numbers file

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(PaperNumbers, EveryCommittedEntryParsesAndCarriesASource) {
  const std::string path = std::string(ACTIONSHIFT_SOURCE_DIR) + "/configs/paper/numbers.json";
  const std::string text = read_text(path);
  ASSERT_FALSE(text.empty()) << path;
  EXPECT_EQ(text, data::builtin_paper_numbers_text()) << "the build embeds another copy than the committed file";
  const PaperNumbers p = parse_paper_numbers(text, path);
  ASSERT_GT(p.entries.size(), 100u);
  const json raw = json::parse(text);
  ASSERT_EQ(raw["entries"].size(), p.entries.size());
  for (const auto& e : p.entries) {
    SCOPED_TRACE(e.id);
    EXPECT_FALSE(e.source.empty());
    EXPECT_TRUE(e.entry.contains("seeds"));
    EXPECT_TRUE(e.entry.contains("episodes"));
    if (e.kind == "difference") {
      EXPECT_TRUE(e.entry.contains("significant"));
    }
  }
  // spot checks against the paper: Table 5 Pick/seen entropy, §5.2's gate clear, Table 2's Push/seen floor
  const PaperNumber* entropy = find_paper_cell(p, "success_once", "pick_cube", "reference_seen", "entropy_probes", "expert");
  ASSERT_NE(entropy, nullptr);
  EXPECT_DOUBLE_EQ(entropy->value, 0.987);
  EXPECT_EQ(entropy->source, "Table 5");
  bool reversed = true;
  const PaperNumber* gain = find_paper_difference(p, "pick_cube", "reference_seen", "entropy_probes", "fixed_probes", "expert", &reversed);
  ASSERT_NE(gain, nullptr);
  EXPECT_FALSE(reversed);
  EXPECT_EQ(gain->interval, std::make_pair(0.037, 0.082));
  EXPECT_EQ(gain->significant, true);
  const PaperNumber* floor = find_paper_cell(p, "success_once", "push_cube", "reference_seen", "no_adapt", "ppo");
  ASSERT_NE(floor, nullptr);
  EXPECT_DOUBLE_EQ(floor->value, 0.003);
  // the delay-aware backbones get Table 4, the reactive ones Table 2
  EXPECT_EQ(find_paper_cell(p, "success_once", "pick_cube", "reference_long_lag", "oracle", "ppo-delay-aware")->source, "Table 4");
  EXPECT_EQ(find_paper_cell(p, "success_once", "pick_cube", "reference_long_lag", "oracle", "expert")->source, "Table 2");
  EXPECT_EQ(builtin_paper_numbers().entries.size(), p.entries.size());
}

TEST(PaperNumbers, BadEntriesAreOneLineErrorsNamingTheField) {
  const auto bad = [](const std::function<void(json&)>& edit) {
    json d = paper_doc();
    edit(d);
    return d.dump();
  };
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][0].erase("source"); }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("p.json: entries[0].source: missing")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][0]["source"] = "somewhere"; }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[0].source: must name a table")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][4]["significant"] = true; }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[4].significant: is true but the interval [-0.0170, 0.0100] includes 0")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][5].erase("note"); }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[5].note: required when \"significant\" is null")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][1]["id"] = "t5.entropy"; }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[1].id: duplicate id")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][1]["quantity"] = "success_once"; }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[1]: matches the same cell or pair as \"t5.entropy\"")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][0]["value"] = 0.9; }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[0].interval: does not contain the value 0.9000")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][0]["method"] = "entropy_probes{x}"; }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[0].method: a paper method is a base name")));
  EXPECT_THAT([&] { parse_paper_numbers(bad([](json& d) { d["entries"][0]["valu"] = 1; }), "p.json"); },
              ThrowsMessage<InputError>(HasSubstr("entries[0].valu: unknown key")));
  EXPECT_THAT([&] { parse_paper_numbers("{\"schema_version\": \"1.0\", \"entries\": [", "p.json"); }, ThrowsMessage<InputError>(HasSubstr("p.json")));
  // a reversed copy of a difference would make the match ambiguous
  EXPECT_THAT([&] {
    parse_paper_numbers(bad([](json& d) {
                          json e = d["entries"][3];
                          e["id"] = "d.sig.reversed";
                          std::swap(e["candidate"], e["baseline"]);
                          d["entries"].push_back(e);
                        }),
                        "p.json");
  }, ThrowsMessage<InputError>(HasSubstr("matches the same cell or pair as \"d.sig\"")));
}

}  // namespace
}  // namespace actionshift::eval
