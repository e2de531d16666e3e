#pragma once
/// \file Gates computed by code (docs/reference.md, *Gates*; docs/formats.md §8): Gate 1 (privileged ceiling: oracle vs no adaptation), promotion rules, and the
/// comparison of verdict files that CI uses to catch regressions.

#include "actionshift/eval/record.hpp"
#include "actionshift/eval/statistics.hpp"
#include "actionshift/eval/summary.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::eval {

// ---------------------------------------------------------------------------------------------
// Paired comparisons over records

/// Paired bootstrap of success_once, candidate − baseline, pairing episodes by PairKey (same seed,
/// contract index and episode index ⇒ same initial state). Pairs are sorted by key before
/// resampling, so the result does not depend on record order.
/// Throws actionshift::InputError (field "pairing") if a key is duplicated within one side, a key
/// is present on only one side (the message counts them and names the first), or paired records
/// disagree on contract_sha256.
BootstrapInterval paired_difference(const std::vector<EpisodeRecord>& candidate,
                                    const std::vector<EpisodeRecord>& baseline, double confidence = 0.95,
                                    std::size_t samples = kBootstrapSamples, std::uint64_t seed = kBootstrapSeed);

/// True iff at least three distinct seeds are given (superiority needs three matched seeds).
bool superiority_allowed(const std::vector<std::uint64_t>& seeds);

// Gate 0 (backbone competence and wrapper parity) is computed where its rollouts are: policy/gate0.hpp.

// ---------------------------------------------------------------------------------------------
// Gate 1: privileged ceiling (issue 5; docs/reference.md, *Gates*)

/// Gate 1 passes a cell when the oracle reaches this success rate (point estimate)…
inline constexpr double kGate1OracleMin = 0.95;
/// …and no adaptation stays at or below this one. Both are the "done when" thresholds: a
/// near-perfect ceiling, and an interface change that breaks the frozen policy.
inline constexpr double kGate1NoAdaptMax = 0.05;
/// Splits that are gated; every other split (long_lag, …) is reported as "descriptive".
inline constexpr std::string_view kGate1GatedSplits[] = {"seen", "unseen_composition"};

/// One (task, split) of Gate 1.
struct Gate1Cell {
  std::string task, split, backbone;
  std::string verdict;        ///< "pass", "fail", "descriptive" (not gated) or "incomplete" (a method missing)
  std::string reason;         ///< why, one line
  std::optional<WilsonInterval> oracle;     ///< success_once of oracle
  std::optional<WilsonInterval> no_adapt;   ///< success_once of no_adapt
  std::optional<BootstrapInterval> difference;  ///< paired oracle − no_adapt
  std::vector<std::uint64_t> seeds;         ///< distinct seeds present
  bool three_seed_comparison{false};        ///< ≥ 3 matched seeds
};

/// All Gate 1 cells.
struct Gate1Report {
  std::vector<Gate1Cell> cells;   ///< sorted by task, split
  std::string claim_status;       ///< "matched_three_seed_ceiling_comparison" if every compared cell has 3 seeds, else "descriptive_only"
  bool passed{false};             ///< every gated cell passes (and there is at least one)
  std::size_t samples{kBootstrapSamples};
  std::uint64_t bootstrap_seed{kBootstrapSeed};
};

/// Gate 1 over records (methods other than oracle and no_adapt are ignored).
/// Throws actionshift::InputError if a cell mixes backbones or the two methods' episode keys differ.
Gate1Report gate1(const std::vector<EpisodeRecord>& records, std::size_t samples = kBootstrapSamples,
                  std::uint64_t bootstrap_seed = kBootstrapSeed);

/// Verdict file (docs/formats.md "Verdict file").
nlohmann::json gate1_to_json(const Gate1Report& report);

/// Markdown table of the cells.
std::string gate1_to_markdown(const Gate1Report& report);

// ---------------------------------------------------------------------------------------------
// Promotion (issue 6; docs/reference.md, *Gates*)

/// Minimum paired gain in success_once over the matched baseline (5 percentage points).
inline constexpr double kPromotionMinGain = 0.05;
/// A one-seed result below this success rate is never promoted (pruning rule).
inline constexpr double kPruneSuccessFloor = 0.3;
/// A Pareto promotion needs at least this candidate success: a cheaper method that ties a failing
/// baseline (for example 0.000 vs 0.000 on a split nothing solves) is not an improvement.
inline constexpr double kParetoSuccessFloor = 0.3;
/// Largest tolerated increase of the flagged-episode rate before it counts as a safety regression.
inline constexpr double kSafetyRegressionTolerance = 0.01;

/// Promotion decision for a candidate method against its matched baseline.
struct PromotionVerdict {
  std::string decision;        ///< "promote", "extend_seeds", "prune" or "reject"
  std::string reason;          ///< one line
  std::size_t matched_seeds{0};
  double candidate_rate{0.0}, baseline_rate{0.0};          ///< success_once
  BootstrapInterval difference;                            ///< paired candidate − baseline
  double candidate_probe_steps{0.0}, baseline_probe_steps{0.0};  ///< mean probe steps (the cost axis)
  double candidate_flag_rate{0.0}, baseline_flag_rate{0.0};      ///< episodes with a safety flag
  bool five_point_rule{false};    ///< estimate ≥ 0.05 and the 95 % interval excludes 0
  bool pareto_rule{false};        ///< strictly fewer mean probe steps, a paired success estimate ≥ 0, candidate
                                  ///< success ≥ kParetoSuccessFloor (so 0.000 vs 0.000 promotes nothing)
  bool safety_regression{false};  ///< flag rate up by > 0.01, or its paired interval lies above 0
};

/// Rules, in order: (1) one seed and candidate success < 0.3 → "prune"; (2) a safety regression →
/// "reject"; (3) fewer than 3 matched seeds → "extend_seeds" (run the promotion seeds); (4) the
/// five-point rule or the Pareto rule → "promote"; otherwise "reject".
/// Throws actionshift::InputError if the two record sets do not pair (see paired_difference).
PromotionVerdict promotion_verdict(const std::vector<EpisodeRecord>& candidate,
                                   const std::vector<EpisodeRecord>& baseline,
                                   std::size_t samples = kBootstrapSamples, std::uint64_t seed = kBootstrapSeed);

/// The fields every promotion JSON shares (a verdict file's cell, a comparison's `promotion`):
/// matched_seeds, candidate/baseline probe steps and safety-flag rates, and the three rule flags.
nlohmann::json promotion_rule_fields(const PromotionVerdict& v);

/// Promotion verdicts of `candidate` against `baseline` for every (task, split, backbone) cell of
/// `records` holding both methods: the verdict file {"gate":"promotion","candidate","baseline",
/// "cells":{"<task>/<split>":{"verdict","reason",...evidence}}} (comparable with gate check).
nlohmann::json promotion_report(const std::vector<EpisodeRecord>& records, const std::string& candidate,
                                const std::string& baseline, std::size_t samples = kBootstrapSamples,
                                std::uint64_t seed = kBootstrapSeed);
/// Markdown table of a promotion report.
std::string promotion_to_markdown(const nlohmann::json& report);

// ---------------------------------------------------------------------------------------------
// Verdict files

/// One cell of a verdict comparison.
struct VerdictChange {
  std::string cell;       ///< cell key, e.g. "pick_cube/seen"
  std::string expected;   ///< expected verdict
  std::string actual;     ///< recomputed verdict ("missing" if absent)
  bool regression{false}; ///< expected a positive verdict ("pass", "advance", "promote"), actual anything else
  std::string line;       ///< one printable line
};

/// Compare two verdict files of the same gate cell by cell (every expected cell, then actual-only
/// cells). Throws actionshift::InputError, naming `expected_source` or `actual_source`, if either is
/// not a verdict file or the gates differ.
std::vector<VerdictChange> compare_verdicts(const nlohmann::json& expected, const nlohmann::json& actual,
                                            const std::string& expected_source = "expected",
                                            const std::string& actual_source = "recomputed verdicts");

}  // namespace actionshift::eval
