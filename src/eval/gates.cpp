#include "actionshift/eval/gates.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/vocabulary.hpp"

#include <nlohmann/json.hpp>
#include <iomanip>

#include <algorithm>
#include <optional>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

namespace actionshift::eval {

namespace {

using nlohmann::json;


json bootstrap_json(const BootstrapInterval& b) {
  return {{"estimate", b.estimate}, {"lower", b.lower},     {"upper", b.upper}, {"confidence", b.confidence},
          {"samples", b.samples},   {"pairs", b.pairs},     {"seed", b.seed}};
}

std::string key_text(const PairKey& k) {
  return "(seed " + std::to_string(k.seed) + ", contract " + std::to_string(k.contract_index) + ", episode " +
         std::to_string(k.episode_index) + ")";
}

std::map<PairKey, const EpisodeRecord*> index_by_key(const std::vector<EpisodeRecord>& records, const char* side) {
  std::map<PairKey, const EpisodeRecord*> out;
  for (const auto& r : records) {
    const PairKey k{r.seed, r.contract_index, r.episode_index};
    if (!out.emplace(k, &r).second)
      throw InputError("", "pairing", std::string("duplicate ") + side + " episode " + key_text(k));
  }
  return out;
}

// matched (candidate, baseline) pairs sorted by key; throws on any mismatch
std::vector<std::pair<const EpisodeRecord*, const EpisodeRecord*>> match_pairs(
    const std::vector<EpisodeRecord>& candidate, const std::vector<EpisodeRecord>& baseline) {
  const auto c = index_by_key(candidate, "candidate");
  const auto b = index_by_key(baseline, "baseline");
  std::size_t only_c = 0, only_b = 0;
  std::optional<PairKey> first;
  for (const auto& [k, r] : c)
    if (!b.count(k)) {
      ++only_c;
      if (!first) first = k;
    }
  for (const auto& [k, r] : b)
    if (!c.count(k)) {
      ++only_b;
      if (!first || k < *first) first = k;
    }
  if (only_c || only_b)
    throw InputError("", "pairing",
                     "episode keys differ: " + std::to_string(only_c) + " only in candidate, " + std::to_string(only_b) +
                         " only in baseline (first " + key_text(*first) + "); finish or remove incomplete jobs");
  if (c.empty()) throw InputError("", "pairing", "no episodes to pair");
  std::vector<std::pair<const EpisodeRecord*, const EpisodeRecord*>> out;
  out.reserve(c.size());
  for (const auto& [k, r] : c) {
    const EpisodeRecord* other = b.at(k);
    if (r->contract_sha256 != other->contract_sha256)
      throw InputError("", "pairing", "episode " + key_text(k) + " ran different contracts (" +
                                          r->contract_sha256.substr(0, 12) + " vs " + other->contract_sha256.substr(0, 12) + ")");
    out.emplace_back(r, other);
  }
  return out;
}

std::vector<std::uint64_t> distinct_seeds(const std::vector<EpisodeRecord>& records) {
  std::set<std::uint64_t> s;
  for (const auto& r : records) s.insert(r.seed);
  return {s.begin(), s.end()};
}

std::int64_t count_success(const std::vector<EpisodeRecord>& records) {
  std::int64_t k = 0;
  for (const auto& r : records) k += r.success_once;
  return k;
}

}  // namespace

BootstrapInterval paired_difference(const std::vector<EpisodeRecord>& candidate,
                                    const std::vector<EpisodeRecord>& baseline, double confidence,
                                    std::size_t samples, std::uint64_t seed) {
  const auto pairs = match_pairs(candidate, baseline);
  std::vector<bool> c, b;
  for (const auto& [rc, rb] : pairs) {
    c.push_back(rc->success_once);
    b.push_back(rb->success_once);
  }
  return paired_success_difference(c, b, confidence, samples, seed);
}

bool superiority_allowed(const std::vector<std::uint64_t>& seeds) {
  return std::set<std::uint64_t>(seeds.begin(), seeds.end()).size() >= 3;
}

// ---- Gate 1

Gate1Report gate1(const std::vector<EpisodeRecord>& records, std::size_t samples, std::uint64_t bootstrap_seed) {
  struct Group {
    std::vector<EpisodeRecord> oracle, no_adapt;
    std::set<std::string> backbones;
  };
  std::map<std::pair<std::string, std::string>, Group> groups;
  for (const auto& r : records) {
    if (r.method != "oracle" && r.method != "no_adapt") continue;
    Group& g = groups[{r.task, r.split}];
    (r.method == "oracle" ? g.oracle : g.no_adapt).push_back(r);
    g.backbones.insert(r.backbone);
  }
  Gate1Report report;
  report.samples = samples;
  report.bootstrap_seed = bootstrap_seed;
  bool all_three = true, any_compared = false, any_gated = false, gated_ok = true;
  for (auto& [key, g] : groups) {
    Gate1Cell c;
    c.task = key.first;
    c.split = key.second;
    const std::string cell = c.task + "/" + c.split;
    if (g.backbones.size() > 1)
      throw InputError("gate1", cell, "mixes backbones (" + *g.backbones.begin() + ", " + *std::next(g.backbones.begin()) +
                                          "); use one results directory per backbone");
    c.backbone = *g.backbones.begin();
    const bool gated = std::find(std::begin(kGate1GatedSplits), std::end(kGate1GatedSplits), c.split) !=
                       std::end(kGate1GatedSplits);
    if (!g.oracle.empty()) c.oracle = wilson_interval(count_success(g.oracle), static_cast<std::int64_t>(g.oracle.size()));
    if (!g.no_adapt.empty())
      c.no_adapt = wilson_interval(count_success(g.no_adapt), static_cast<std::int64_t>(g.no_adapt.size()));
    if (c.oracle && c.no_adapt) {
      try {
        c.difference = paired_difference(g.oracle, g.no_adapt, 0.95, samples, bootstrap_seed);
      } catch (const InputError& e) {
        throw InputError("gate1", cell, "oracle vs no_adapt: " + e.reason());
      }
      c.seeds = distinct_seeds(g.oracle);
      c.three_seed_comparison = superiority_allowed(c.seeds);
      any_compared = true;
      all_three = all_three && c.three_seed_comparison;
      const std::string rates = "oracle " + fixed(c.oracle->rate, 4) + ", no_adapt " + fixed(c.no_adapt->rate, 4);
      if (!gated) {
        c.verdict = verdict_name(Verdict::kDescriptive);
        c.reason = rates + " (split '" + c.split + "' is not gated: only seen and unseen_composition are)";
      } else if (c.oracle->rate >= kGate1OracleMin && c.no_adapt->rate <= kGate1NoAdaptMax) {
        c.verdict = verdict_name(Verdict::kPass);
        c.reason = rates;
      } else {
        c.verdict = verdict_name(Verdict::kFail);
        if (c.oracle->rate < kGate1OracleMin) c.reason = "oracle " + fixed(c.oracle->rate, 4) + " below " + fixed(kGate1OracleMin, 4);
        if (c.no_adapt->rate > kGate1NoAdaptMax)
          c.reason += (c.reason.empty() ? "" : "; ") + std::string("no_adapt ") + fixed(c.no_adapt->rate, 4) + " above " +
                      fixed(kGate1NoAdaptMax, 4);
      }
    } else {
      c.seeds = distinct_seeds(g.oracle.empty() ? g.no_adapt : g.oracle);
      c.verdict = verdict_name(gated ? Verdict::kIncomplete : Verdict::kDescriptive);
      c.reason = std::string("no ") + (c.oracle ? "no_adapt" : "oracle") + " records";
    }
    if (gated) {
      any_gated = true;
      gated_ok = gated_ok && c.verdict == verdict_name(Verdict::kPass);
    }
    report.cells.push_back(std::move(c));
  }
  report.claim_status = any_compared && all_three ? "matched_three_seed_ceiling_comparison" : "descriptive_only";
  report.passed = any_gated && gated_ok;
  return report;
}

nlohmann::json gate1_to_json(const Gate1Report& report) {
  json j = {{"schema_version", "1.0"},
            {"gate", "gate1"},
            {"thresholds",
             {{"oracle_min", kGate1OracleMin},
              {"no_adapt_max", kGate1NoAdaptMax},
              {"statistic", "success_once point estimate"},
              {"gated_splits", json::array({kGate1GatedSplits[0], kGate1GatedSplits[1]})}}},
            {"bootstrap", {{"samples", report.samples}, {"seed", report.bootstrap_seed}, {"confidence", 0.95}}},
            {"claim_status", report.claim_status},
            {"passed", report.passed},
            {"cells", json::object()}};
  for (const auto& c : report.cells) {
    j["cells"][c.task + "/" + c.split] = {
        {"task", c.task},
        {"split", c.split},
        {"backbone", c.backbone},
        {"verdict", c.verdict},
        {"reason", c.reason},
        {"oracle", c.oracle ? wilson_json(*c.oracle) : json(nullptr)},
        {"no_adapt", c.no_adapt ? wilson_json(*c.no_adapt) : json(nullptr)},
        {"oracle_minus_no_adapt", c.difference ? bootstrap_json(*c.difference) : json(nullptr)},
        {"seeds", c.seeds},
        {"three_seed_comparison", c.three_seed_comparison},
        {"interpretation", "privileged ceiling gap; not an adaptation-method superiority claim"}};
  }
  return j;
}

std::string gate1_to_markdown(const Gate1Report& report) {
  auto w = [](const std::optional<WilsonInterval>& x) {
    return x ? fixed(x->rate, 3) + " [" + fixed(x->lower, 3) + ", " + fixed(x->upper, 3) + "]" : std::string("—");
  };
  std::ostringstream s;
  s << "| task | split | oracle (Wilson 95 %) | no_adapt (Wilson 95 %) | paired diff (bootstrap 95 %) | seeds | verdict |\n"
    << "|---|---|---|---|---|---:|---|\n";
  for (const auto& c : report.cells) {
    const std::string d = c.difference ? fixed(c.difference->estimate, 3) + " [" + fixed(c.difference->lower, 3) + ", " +
                                             fixed(c.difference->upper, 3) + "]"
                                       : std::string("—");
    s << "| " << c.task << " | " << c.split << " | " << w(c.oracle) << " | " << w(c.no_adapt) << " | " << d << " | "
      << c.seeds.size() << " | " << c.verdict << " |\n";
  }
  bool any_gated = false;
  for (const auto& c : report.cells) {
    if (c.verdict == verdict_name(Verdict::kPass)) continue;
    if (c.verdict != verdict_name(Verdict::kDescriptive)) any_gated = true;
    s << "\n- " << c.task << "/" << c.split << " is "
      << c.verdict << ": " << c.reason;
  }
  for (const auto& c : report.cells) any_gated = any_gated || c.verdict == verdict_name(Verdict::kPass);
  bool listed = false;
  for (const auto& c : report.cells) listed = listed || c.verdict != verdict_name(Verdict::kPass);
  if (listed) s << "\n";
  s << "\nclaim status: " << report.claim_status << "; gate 1 " << (report.passed ? "passed" : "not passed");
  if (!report.passed && !any_gated) s << " (no gated cell: Gate 1 needs oracle and no_adapt on seen or unseen_composition)";
  s << "\n";
  return s.str();
}

// ---- promotion

PromotionVerdict promotion_verdict(const std::vector<EpisodeRecord>& candidate, const std::vector<EpisodeRecord>& baseline,
                                   std::size_t samples, std::uint64_t seed) {
  const auto pairs = match_pairs(candidate, baseline);
  PromotionVerdict v;
  const double n = static_cast<double>(pairs.size());
  std::vector<bool> cs, bs, cf, bf;
  double c_probe = 0.0, b_probe = 0.0;
  for (const auto& [c, b] : pairs) {
    cs.push_back(c->success_once);
    bs.push_back(b->success_once);
    cf.push_back(!c->safety_flags.empty());
    bf.push_back(!b->safety_flags.empty());
    c_probe += static_cast<double>(c->probe_steps);
    b_probe += static_cast<double>(b->probe_steps);
  }
  v.matched_seeds = distinct_seeds(candidate).size();
  v.difference = paired_success_difference(cs, bs, 0.95, samples, seed);
  v.candidate_rate = static_cast<double>(std::count(cs.begin(), cs.end(), true)) / n;
  v.baseline_rate = static_cast<double>(std::count(bs.begin(), bs.end(), true)) / n;
  v.candidate_probe_steps = c_probe / n;
  v.baseline_probe_steps = b_probe / n;
  v.candidate_flag_rate = static_cast<double>(std::count(cf.begin(), cf.end(), true)) / n;
  v.baseline_flag_rate = static_cast<double>(std::count(bf.begin(), bf.end(), true)) / n;
  const BootstrapInterval flag_diff = paired_success_difference(cf, bf, 0.95, samples, seed);
  v.safety_regression = v.candidate_flag_rate - v.baseline_flag_rate > kSafetyRegressionTolerance || flag_diff.lower > 0.0;
  v.five_point_rule = v.difference.estimate >= kPromotionMinGain - 1e-12 && v.difference.lower > 0.0;
  // a Pareto point on (success, probe cost): strictly cheaper, not less successful, and successful
  // enough that the tie means something (0.000 vs 0.000 on an unsolved split promotes nothing)
  v.pareto_rule = v.candidate_probe_steps < v.baseline_probe_steps && v.difference.estimate >= 0.0 &&
                  v.candidate_rate >= kParetoSuccessFloor;
  const std::string diff = fixed(v.difference.estimate, 4) + " [" + fixed(v.difference.lower, 4) + ", " +
                           fixed(v.difference.upper, 4) + "]";
  if (v.matched_seeds == 1 && v.candidate_rate < kPruneSuccessFloor) {
    v.decision = verdict_name(Verdict::kPrune);
    v.reason = "one-seed success " + fixed(v.candidate_rate, 4) + " below " + fixed(kPruneSuccessFloor, 4) +
               "; a sub-0.3 one-seed result is never promoted";
  } else if (v.safety_regression) {
    v.decision = verdict_name(Verdict::kReject);
    v.reason = "safety regression: flagged-episode rate " + fixed(v.candidate_flag_rate, 4) + " vs baseline " +
               fixed(v.baseline_flag_rate, 4);
  } else if (v.matched_seeds < 3) {
    v.decision = verdict_name(Verdict::kExtendSeeds);
    v.reason = "superiority requires at least three matched seeds (have " + std::to_string(v.matched_seeds) +
               "); difference " + diff;
  } else if (v.five_point_rule || v.pareto_rule) {
    v.decision = verdict_name(Verdict::kPromote);
    v.reason = v.five_point_rule ? "difference " + diff + " at least " + fixed(kPromotionMinGain, 4)
                                 : "Pareto point: probe steps " + fixed(v.candidate_probe_steps, 2) + " vs " +
                                       fixed(v.baseline_probe_steps, 2) + ", difference " + diff;
  } else {
    v.decision = verdict_name(Verdict::kReject);
    const bool cheaper_tie = v.candidate_probe_steps < v.baseline_probe_steps && v.difference.estimate >= 0.0;
    v.reason = "difference " + diff + " below " + fixed(kPromotionMinGain, 4) +
               (cheaper_tie ? " and success " + fixed(v.candidate_rate, 4) + " below the Pareto floor " + fixed(kParetoSuccessFloor, 4)
                            : " and no Pareto improvement in probe steps (" + fixed(v.candidate_probe_steps, 2) + " vs " +
                                  fixed(v.baseline_probe_steps, 2) + ")");
  }
  return v;
}

// ---- verdict files

namespace {
// episodes a verdict cell rests on: its "episodes" field, else the smallest "total" of the Wilson
// intervals it holds (gate 1: oracle and no_adapt); nullopt when the cell states neither
std::optional<std::int64_t> cell_episodes(const json& cell) {
  if (cell.contains("episodes") && cell["episodes"].is_number_integer()) return cell["episodes"].get<std::int64_t>();
  std::optional<std::int64_t> n;
  for (const char* k : {"oracle", "no_adapt", "competence"}) {
    if (!cell.contains(k) || !cell[k].is_object() || !cell[k].contains("total") || !cell[k]["total"].is_number_integer()) continue;
    const auto t = cell[k]["total"].get<std::int64_t>();
    n = n ? std::min(*n, t) : t;
  }
  return n;
}
}  // namespace

std::vector<VerdictChange> compare_verdicts(const nlohmann::json& expected, const nlohmann::json& actual,
                                            const std::string& source, const std::string& actual_source) {
  auto check = [&](const json& j, const std::string& name) {
    if (!j.is_object() || !j.contains("gate") || !j["gate"].is_string() || !j.contains("cells") || !j["cells"].is_object())
      throw InputError(name, "cells", "not a verdict file (needs \"gate\" and a \"cells\" object)");
    for (auto it = j["cells"].begin(); it != j["cells"].end(); ++it) {
      if (!it.value().is_object() || !it.value().contains("verdict") || !it.value()["verdict"].is_string())
        throw InputError(name, "cells." + it.key() + ".verdict", "missing verdict string");
      (void)parse_verdict(it.value()["verdict"].get<std::string>(), name, "cells." + it.key() + ".verdict");
    }
  };
  check(expected, source);
  check(actual, actual_source);
  // an expectation with no cells would pass whatever the results say
  if (expected["cells"].empty()) throw InputError(source, "cells", "no verdicts to check (the file's cells object is empty)");
  if (expected["gate"] != actual["gate"])
    throw InputError(source, "gate", "expected verdicts are for " + expected["gate"].get<std::string>() + ", not " +
                                         actual["gate"].get<std::string>());
  std::vector<VerdictChange> out;
  const json& ec = expected["cells"];
  const json& ac = actual["cells"];
  for (auto it = ec.begin(); it != ec.end(); ++it) {
    VerdictChange c;
    c.cell = it.key();
    c.expected = it.value()["verdict"].get<std::string>();
    const bool present = ac.contains(c.cell);
    c.actual = present ? ac[c.cell]["verdict"].get<std::string>() : "missing";
    // a positive verdict (gate1 "pass", gate0 "advance", promotion "promote") that is lost regresses
    const bool positive = is_positive(parse_verdict(c.expected));
    c.regression = positive && c.actual != c.expected;
    std::string reason = present && ac[c.cell].contains("reason") && ac[c.cell]["reason"].is_string()
                             ? ac[c.cell]["reason"].get<std::string>()
                             : std::string();
    // a verdict recomputed from fewer episodes than the expectation it is compared with proves nothing
    const auto want = cell_episodes(it.value());
    const auto have = present ? cell_episodes(ac[c.cell]) : std::nullopt;
    if (want && have && *have < *want) {
      c.regression = true;
      reason = "rests on " + std::to_string(*have) + " episodes, fewer than the expected verdict's " + std::to_string(*want) +
               (reason.empty() ? "" : "; " + reason);
    }
    const char* tag = c.regression ? "REGRESSION" : c.expected == c.actual ? "ok" : (present && is_positive(parse_verdict(c.actual)) ? "improved" : "changed");
    c.line = std::string(tag) + " " + c.cell + ": expected " + c.expected + ", got " + c.actual +
             (reason.empty() ? "" : " (" + reason + ")");
    out.push_back(std::move(c));
  }
  for (auto it = ac.begin(); it != ac.end(); ++it) {
    if (ec.contains(it.key())) continue;
    VerdictChange c;
    c.cell = it.key();
    c.expected = "none";
    c.actual = it.value()["verdict"].get<std::string>();
    c.line = "new " + c.cell + ": got " + c.actual;
    out.push_back(std::move(c));
  }
  return out;
}


json promotion_rule_fields(const PromotionVerdict& v) {
  return {{"matched_seeds", v.matched_seeds},
          {"candidate_probe_steps", v.candidate_probe_steps},
          {"baseline_probe_steps", v.baseline_probe_steps},
          {"candidate_flag_rate", v.candidate_flag_rate},
          {"baseline_flag_rate", v.baseline_flag_rate},
          {"five_point_rule", v.five_point_rule},
          {"pareto_rule", v.pareto_rule},
          {"safety_regression", v.safety_regression}};
}

json promotion_report(const std::vector<EpisodeRecord>& records, const std::string& candidate, const std::string& baseline,
                      std::size_t samples, std::uint64_t seed) {
  // group by (task, split, backbone); keep cells where both methods ran
  std::map<std::string, std::pair<std::vector<EpisodeRecord>, std::vector<EpisodeRecord>>> cells;
  for (const auto& r : records) {
    if (r.method_variant != candidate && r.method_variant != baseline) continue;
    const std::string key = r.task + "/" + r.split + (r.backbone == "expert" ? "" : "/" + r.backbone);
    (r.method_variant == candidate ? cells[key].first : cells[key].second).push_back(r);
  }
  json j = {{"schema_version", "1.0"},
            {"gate", "promotion"},
            {"candidate", candidate},
            {"baseline", baseline},
            {"rules",
             {{"min_gain", kPromotionMinGain},
              {"prune_below_one_seed", kPruneSuccessFloor},
              {"pareto_success_floor", kParetoSuccessFloor},
              {"safety_regression_tolerance", kSafetyRegressionTolerance},
              {"order", "prune (one seed < 0.3), reject on a safety regression, extend_seeds (< 3 matched seeds), "
                        "promote on >= 5 points with the paired 95 % interval above 0 or on a Pareto point "
                        "(fewer mean probe steps, paired success estimate >= 0, candidate success >= 0.3), else reject"}}},
            {"bootstrap", {{"samples", samples}, {"seed", seed}}},
            {"cells", json::object()}};
  for (const auto& [key, pair] : cells) {
    if (pair.first.empty() || pair.second.empty()) continue;
    PromotionVerdict v;
    try {
      v = promotion_verdict(pair.first, pair.second, samples, seed);
    } catch (const InputError& e) {
      throw InputError("promotion", key, candidate + " vs " + baseline + ": " + e.reason());
    }
    j["cells"][key] = {{"task", pair.first.front().task},
                       {"split", pair.first.front().split},
                       {"backbone", pair.first.front().backbone},
                       {"verdict", v.decision},
                       {"reason", v.reason},
                       {"episodes", static_cast<std::int64_t>(std::min(pair.first.size(), pair.second.size()))},
                       {"candidate_success", v.candidate_rate},
                       {"baseline_success", v.baseline_rate},
                       {"difference", bootstrap_json(v.difference)}};
    j["cells"][key].update(promotion_rule_fields(v));
  }
  return j;
}

std::string promotion_to_markdown(const json& report) {
  std::ostringstream o;
  o << "Promotion: " << report["candidate"].get<std::string>() << " vs " << report["baseline"].get<std::string>() << "\n\n"
    << "| cell | candidate | baseline | difference [95 % CI] | probe steps (cand / base) | seeds | verdict | reason |\n"
    << "|---|---:|---:|---|---|---:|---|---|\n";
  auto f3 = [](double x) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(3) << x;
    return s.str();
  };
  for (auto it = report["cells"].begin(); it != report["cells"].end(); ++it) {
    const json& c = it.value();
    const json& d = c["difference"];
    o << "| " << it.key() << " | " << f3(c["candidate_success"].get<double>()) << " | " << f3(c["baseline_success"].get<double>())
      << " | " << f3(d["estimate"].get<double>()) << " [" << f3(d["lower"].get<double>()) << ", " << f3(d["upper"].get<double>())
      << "] | " << f3(c["candidate_probe_steps"].get<double>()) << " / " << f3(c["baseline_probe_steps"].get<double>()) << " | "
      << c["matched_seeds"].get<std::size_t>() << " | **" << c["verdict"].get<std::string>() << "** | "
      << c["reason"].get<std::string>() << " |\n";
  }
  return o.str();
}

}  // namespace actionshift::eval
