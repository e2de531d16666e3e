#pragma once
/// \file One statistics engine for results pages (`actionshift compare`; docs/formats.md "Comparison"
/// and "Paper numbers"): per cell the success rate with its Wilson interval, per-seed rates, probe
/// cost and safety flags; per pair of method labels and (task, split, backbone) the paired bootstrap
/// difference, its per-seed differences and the promotion verdict (gates.hpp); the paper's numbers
/// (configs/paper/numbers.json) beside ours.

#include "actionshift/eval/record.hpp"
#include "actionshift/eval/statistics.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace actionshift::eval {

/// Version of the comparison JSON written by compare_records.
inline constexpr std::string_view kComparisonSchemaVersion = "1.0";
/// Version of the paper-numbers file this build reads.
inline constexpr std::string_view kPaperNumbersSchemaVersion = "1.0";

/// A comparison of two method labels (opaque strings, e.g. `entropy_probes` or
/// `entropy_probes{calibrated}`): candidate − baseline. Without backbones both sides run on the same
/// backbone (compared in every (task, split, backbone)); with them (`LABEL@BACKBONE` on both sides) the
/// candidate's cell on one backbone is compared with the baseline's on another, in every (task, split).
struct ComparisonPair {
  std::string candidate;
  std::string baseline;
  std::string candidate_backbone{};  ///< non-empty only in a cross-backbone pair (then so is baseline_backbone)
  std::string baseline_backbone{};
  bool cross_backbone() const { return !candidate_backbone.empty(); }
  std::string candidate_side() const;  ///< `LABEL` or `LABEL@BACKBONE`, as written
  std::string baseline_side() const;
  std::string text() const;  ///< `CANDIDATE vs BASELINE`, as written
  bool operator==(const ComparisonPair&) const = default;
};

/// Parse `CANDIDATE vs BASELINE` (exactly one " vs ", both sides non-empty and different; labels may
/// hold `{`, `,`, `=`). A side may name a backbone, `LABEL@BACKBONE`: the first `@` outside the label's
/// `{...}` separates (a method name holds no `@`; an `@` inside the braces, a parameter's text, is part
/// of the label; a backbone name may hold `@`). Both sides name a backbone or neither. Throws
/// InputError(source, field, reason).
ComparisonPair parse_comparison_pair(std::string_view text, const std::string& source, const std::string& field);

/// The pairs of a pairs file: one `CANDIDATE vs BASELINE` per line; blank lines and lines starting
/// with `#` are ignored. Errors name `<source>:<line>`.
std::vector<ComparisonPair> parse_pairs_text(std::string_view text, const std::string& source);

/// The method's base name: the label before its first `{` (the whole label if it has none).
std::string method_base_name(std::string_view label);

/// One entry of the paper-numbers file (docs/formats.md "Paper numbers").
struct PaperNumber {
  std::string id;                 ///< unique, e.g. "table5.pick_cube.reference_seen.entropy_probes.success"
  std::string kind;               ///< "cell", "difference" or "scalar"
  std::string quantity;           ///< e.g. "success_once", "mean_probe_steps", "success_difference"
  std::string task, split;        ///< cell and difference entries
  std::string method;             ///< cell entries: the paper's method (a base name, no `{`)
  std::string candidate, baseline;  ///< difference entries
  std::string variant;            ///< non-empty: a configuration other than the method's default; never matched to cells
  std::vector<std::string> backbones;  ///< our backbones the number is set beside; empty: any backbone
  double value{0.0};
  std::optional<std::pair<double, double>> interval;  ///< the paper's 95 % interval, if it gives one
  std::optional<bool> significant;  ///< difference entries: the paper's interval excludes 0; nullopt: not known
  std::string source;             ///< where in the paper ("Table 5", "§5.8", "Fig. 4") or "reference implementation ..."
  nlohmann::json entry;           ///< the entry as written in the file (what the comparison prints)
};

/// A parsed paper-numbers file.
struct PaperNumbers {
  std::string source;              ///< file path, or "built-in configs/paper/numbers.json"
  std::vector<PaperNumber> entries;
};

/// Parse and validate a paper-numbers file. Throws InputError(source, "entries[i].<field>", reason)
/// for a missing or mistyped field, a duplicate id, two entries that would match the same cell or pair
/// with the same backbone scope, or a difference whose `significant` contradicts its interval.
PaperNumbers parse_paper_numbers(std::string_view text, const std::string& source);

/// The paper-numbers file compiled into this build (configs/paper/numbers.json).
PaperNumbers builtin_paper_numbers();

/// The paper's number for a cell quantity: the entry whose backbones list `backbone` wins over one
/// that names no backbone; nullptr if none (or `method` carries a `{...}` suffix).
const PaperNumber* find_paper_cell(const PaperNumbers& paper, std::string_view quantity, std::string_view task,
                                   std::string_view split, std::string_view method, std::string_view backbone);

/// The paper's difference for a pair (as find_paper_cell). `*reversed` is set when the entry is
/// baseline − candidate (its value and interval are then to be negated).
const PaperNumber* find_paper_difference(const PaperNumbers& paper, std::string_view task, std::string_view split,
                                         std::string_view candidate, std::string_view baseline, std::string_view backbone,
                                         bool* reversed);

/// What was read, for the `inputs` block of the comparison.
struct CompareInputs {
  struct Directory {
    std::string dir;
    std::vector<std::string> files;
    std::size_t records{0};
    std::vector<std::string> notes;
  };
  std::vector<Directory> directories;
};

/// The comparison of `records` (docs/formats.md "Comparison"). Cells are those of summarize_records,
/// each with its per-contract counts and Wilson intervals (an error naming the cell if one contract
/// index carries two contract hashes); each same-backbone pair is compared in every (task, split,
/// backbone) holding both labels, each cross-backbone pair in every (task, split) holding both cells, with
/// paired_success_difference over the pairs sorted by PairKey (kBootstrapSamples resamples, seed
/// kBootstrapSeed) and promotion_verdict. Throws InputError naming the cell if a pair's two cells do
/// not hold the same episodes (seed, contract, episode index) or ran different contracts, and naming
/// the pair if no (task, split, backbone) holds both labels (no (task, split) both cells).
/// `common_episodes`: pair only the episodes both cells hold instead of refusing cells whose episode sets
/// differ (a job's first M episodes are the M-episode job's, so a 50-episode cell pairs with the first 50
/// of a 200-episode one); each comparison then says in `unpaired` how many episodes of each side it left out.
///
/// `across_backbones`: also the comparison's `across_backbones` list. For each same-backbone pair and
/// each (task, split) where two or more backbones hold both labels: per backbone the paired difference
/// with the cluster bootstrap over (seed, block), a block being the episodes that share an initial
/// state (episode_index / the cell's contract count); pooled, hierarchical_bootstrap over backbones,
/// then seeds, then blocks (the backbone a random effect), each with kBootstrapSamples resamples and
/// seed kBootstrapSeed; and a verdict: `holds_on_every_backbone` (the pooled interval and every
/// backbone's exclude 0 with one sign), `holds_on_average` (the pooled interval excludes 0, some
/// backbone's does not), `depends_on_backbone` (backbones significant with opposite signs, or the
/// pooled interval includes 0 while some backbone's excludes it) or `not_shown` (no interval excludes 0).
nlohmann::json compare_records(const std::vector<EpisodeRecord>& records, const std::vector<ComparisonPair>& pairs,
                               const PaperNumbers& paper, const CompareInputs& inputs = {}, bool common_episodes = false,
                               bool across_backbones = false);

/// load_results of every directory, then compare_records. Throws InputError for a directory without
/// records (naming it) and as compare_records.
nlohmann::json compare_directories(const std::vector<std::string>& dirs, const std::vector<ComparisonPair>& pairs,
                                   const PaperNumbers& paper, bool common_episodes = false, bool across_backbones = false);

}  // namespace actionshift::eval
