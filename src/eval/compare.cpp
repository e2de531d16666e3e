#include "actionshift/eval/compare.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/vocabulary.hpp"
#include "actionshift/data/paper_numbers.hpp"
#include "actionshift/eval/gates.hpp"
#include "actionshift/eval/summary.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>

namespace actionshift::eval {

namespace {

using nlohmann::json;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// ---- the paper-numbers file

const std::set<std::string, std::less<>> kEntryKeys = {
    "id",     "kind",  "quantity", "task",     "split",    "method", "candidate", "baseline",    "variant",
    "backbones", "paper_backbone", "value", "interval", "unit", "source", "seeds", "episodes", "per_seed",
    "significant", "note", "seed_count"};

// where in the paper: a table, a section, a figure or an appendix; or the reference implementation
bool valid_source(const std::string& s) {
  const auto digit_after = [&](std::string_view prefix) {
    return s.rfind(prefix, 0) == 0 && s.size() > prefix.size() && std::isdigit(static_cast<unsigned char>(s[prefix.size()]));
  };
  if (digit_after("Table ") || digit_after("Fig. ") || digit_after("§")) return true;
  if (s.rfind("Appendix ", 0) == 0 && s.size() > 9 && s[9] >= 'A' && s[9] <= 'Z') return true;
  return s.rfind("reference implementation", 0) == 0;
}

struct EntryReader {
  const json& e;
  const std::string& source;
  std::string path;  // "entries[i]"

  [[noreturn]] void fail(const std::string& field, const std::string& reason) const {
    throw InputError(source, path + (field.empty() ? "" : "." + field), reason);
  }
  bool has(const char* k) const { return e.contains(k) && !e[k].is_null(); }
  std::string str(const char* k, bool required) const {
    if (!e.contains(k)) {
      if (required) fail(k, "missing");
      return {};
    }
    if (!e[k].is_string()) fail(k, "must be a string (got " + json_for_message(e[k]) + ")");
    const std::string v = e[k].get<std::string>();
    if (v.empty()) fail(k, "must not be empty");
    return v;
  }
  double number(const json& v, const std::string& field) const {
    if (!v.is_number()) fail(field, "must be a number (got " + json_for_message(v) + ")");
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(field, "must be finite");
    return x;
  }
};

PaperNumber parse_entry(const json& e, const std::string& source, std::size_t index) {
  const EntryReader r{e, source, "entries[" + std::to_string(index) + "]"};
  if (!e.is_object()) r.fail("", "must be an object (got " + json_for_message(e) + ")");
  for (auto it = e.begin(); it != e.end(); ++it)
    if (!kEntryKeys.count(it.key())) r.fail(it.key(), "unknown key (docs/formats.md \"Paper numbers\" lists the keys)");
  PaperNumber p;
  p.entry = e;
  p.id = r.str("id", true);
  p.kind = r.str("kind", true);
  if (p.kind != "cell" && p.kind != "difference" && p.kind != "scalar")
    r.fail("kind", "must be \"cell\", \"difference\" or \"scalar\" (got " + quote_input(p.kind, '"') + ")");
  p.quantity = r.str("quantity", true);
  p.source = r.str("source", true);
  if (!valid_source(p.source))
    r.fail("source", "must name a table, section, figure or appendix of the paper (\"Table 5\", \"§5.8\", \"Fig. 4\", "
                     "\"Appendix C\") or start with \"reference implementation\" (got " + quote_input(p.source, '"') + ")");
  if (!e.contains("value")) r.fail("value", "missing");
  p.value = r.number(e["value"], "value");
  const bool needs_cell = p.kind != "scalar";
  p.task = r.str("task", needs_cell);
  p.split = r.str("split", needs_cell);
  p.variant = r.str("variant", false);
  if (p.kind == "cell") {
    p.method = r.str("method", true);
    if (p.method.find('{') != std::string::npos) r.fail("method", "a paper method is a base name (no '{'); describe a configuration in \"variant\"");
  } else if (p.kind == "scalar") {
    p.method = r.str("method", false);  // descriptive only: a scalar is never matched to a cell
  } else if (e.contains("method")) {
    r.fail("method", "a difference names a candidate and a baseline, not a method");
  }
  if (p.kind == "difference") {
    p.candidate = r.str("candidate", true);
    p.baseline = r.str("baseline", true);
    if (p.candidate == p.baseline) r.fail("baseline", "equals the candidate");
    for (const auto* k : {"candidate", "baseline"})
      if (e[k].get<std::string>().find('{') != std::string::npos)
        r.fail(k, "a paper method is a base name (no '{'); describe a configuration in \"variant\"");
  } else {
    for (const auto* k : {"candidate", "baseline"})
      if (e.contains(k)) r.fail(k, "only difference entries name a candidate and a baseline");
  }
  if (e.contains("backbones")) {
    const json& b = e["backbones"];
    if (!b.is_array() || b.empty()) r.fail("backbones", "must be a non-empty array of backbone names (leave it out for any backbone)");
    for (std::size_t i = 0; i < b.size(); ++i) {
      if (!b[i].is_string() || b[i].get<std::string>().empty())
        r.fail("backbones[" + std::to_string(i) + "]", "must be a non-empty string");
      p.backbones.push_back(b[i].get<std::string>());
    }
  }
  if (e.contains("interval")) {
    const json& iv = e["interval"];
    if (!iv.is_array() || iv.size() != 2) r.fail("interval", "must be [lower, upper]");
    const double lo = r.number(iv[0], "interval[0]"), hi = r.number(iv[1], "interval[1]");
    if (lo > hi) r.fail("interval", "lower above upper");
    // printed values are rounded to 3 decimals (differences in points to 1 decimal of a point)
    if (p.value < lo - 0.0015 || p.value > hi + 0.0015) r.fail("interval", "does not contain the value " + fixed(p.value, 4));
    p.interval = std::make_pair(lo, hi);
  }
  if (!e.contains("seeds")) r.fail("seeds", "missing (an empty array when the paper does not say)");
  if (!e["seeds"].is_array()) r.fail("seeds", "must be an array of seeds");
  for (std::size_t i = 0; i < e["seeds"].size(); ++i)
    if (!e["seeds"][i].is_number_unsigned()) r.fail("seeds[" + std::to_string(i) + "]", "must be a non-negative integer");
  if (e.contains("seed_count")) {
    if (!(e["seed_count"].is_number_unsigned() && e["seed_count"].get<std::uint64_t>() > 0))
      r.fail("seed_count", "must be a positive integer");
    if (!e["seeds"].empty() && e["seed_count"].get<std::uint64_t>() != e["seeds"].size())
      r.fail("seed_count", "differs from the number of seeds listed");
  }
  if (!e.contains("episodes")) r.fail("episodes", "missing (null when the paper does not say)");
  if (!e["episodes"].is_null() && !(e["episodes"].is_number_unsigned() && e["episodes"].get<std::uint64_t>() > 0))
    r.fail("episodes", "must be a positive integer or null");
  if (e.contains("per_seed")) {
    const json& ps = e["per_seed"];
    if (!ps.is_array() || ps.empty()) r.fail("per_seed", "must be a non-empty array of {\"seed\", \"rate\"}");
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const std::string f = "per_seed[" + std::to_string(i) + "]";
      if (!ps[i].is_object() || ps[i].size() != 2 || !ps[i].contains("seed") || !ps[i].contains("rate") ||
          !ps[i]["seed"].is_number_unsigned())
        r.fail(f, "must be {\"seed\": integer, \"rate\": number}");
      const double rate = r.number(ps[i]["rate"], f + ".rate");
      if (rate < 0.0 || rate > 1.0) r.fail(f + ".rate", "must be in [0, 1]");
    }
  }
  for (const auto* k : {"note", "unit", "paper_backbone"})
    if (e.contains(k)) (void)r.str(k, false);
  if (p.kind == "difference") {
    if (!e.contains("significant")) r.fail("significant", "missing (true, false, or null with a note)");
    const json& s = e["significant"];
    if (s.is_null()) {
      if (!e.contains("note")) r.fail("note", "required when \"significant\" is null: say why the paper's significance is unknown");
    } else if (s.is_boolean()) {
      p.significant = s.get<bool>();
      if (p.interval) {
        const bool excludes = p.interval->first > 0.0 || p.interval->second < 0.0;
        if (excludes != *p.significant)
          r.fail("significant", std::string("is ") + (*p.significant ? "true" : "false") + " but the interval [" +
                                    fixed(p.interval->first, 4) + ", " + fixed(p.interval->second, 4) + "] " +
                                    (excludes ? "excludes" : "includes") + " 0");
      }
    } else {
      r.fail("significant", "must be true, false or null");
    }
  } else if (e.contains("significant")) {
    r.fail("significant", "only difference entries carry a significance");
  }
  return p;
}

// the (kind, quantity, task, split, method or sorted pair) an entry is matched on; "" for entries never matched
std::string match_key(const PaperNumber& p) {
  if (p.kind == "scalar" || !p.variant.empty()) return {};
  if (p.kind == "cell") return "cell\n" + p.quantity + "\n" + p.task + "\n" + p.split + "\n" + p.method;
  const auto [a, b] = std::minmax(p.candidate, p.baseline);
  return "difference\n" + p.quantity + "\n" + p.task + "\n" + p.split + "\n" + a + "\n" + b;
}

// entry of `candidates` whose backbones name `backbone`, else the one naming none
const PaperNumber* most_specific(const std::vector<const PaperNumber*>& candidates, std::string_view backbone) {
  const PaperNumber* any = nullptr;
  for (const PaperNumber* p : candidates) {
    if (p->backbones.empty()) any = p;
    else if (std::find(p->backbones.begin(), p->backbones.end(), backbone) != p->backbones.end()) return p;
  }
  return any;
}

// ---- records

std::string key_text(const PairKey& k) {
  return "(seed " + std::to_string(k.seed) + ", contract " + std::to_string(k.contract_index) + ", episode " +
         std::to_string(k.episode_index) + ")";
}

// the summary owns the rule that names a record's cell (its method label): deriving the key through

std::string cell_text(const CellKey& k) { return k.task + "/" + k.split + "/" + k.method + "/" + k.backbone; }

// per contract index: its hash, episodes and success_once count; one hash per index
json per_contract_json(const CellKey& key, const std::vector<EpisodeRecord>& records) {
  struct Count {
    std::string sha;
    std::int64_t episodes{0}, successes{0};
  };
  std::map<std::int64_t, Count> by_index;
  for (const auto& r : records) {
    auto [it, fresh] = by_index.try_emplace(r.contract_index, Count{r.contract_sha256});
    if (!fresh && it->second.sha != r.contract_sha256)
      throw InputError("results", cell_text(key),
                       "contract index " + std::to_string(r.contract_index) + " carries two contract hashes (" +
                           it->second.sha.substr(0, 12) + " and " + r.contract_sha256.substr(0, 12) +
                           "): records of different split definitions in one cell");
    ++it->second.episodes;
    it->second.successes += r.success_once ? 1 : 0;
  }
  json out = json::array();
  for (const auto& [index, c] : by_index)
    out.push_back({{"contract_index", index},
                   {"contract_sha256", c.sha},
                   {"episodes", c.episodes},
                   {"successes", c.successes},
                   {"success_once", wilson_json(wilson_interval(c.successes, c.episodes))}});
  return out;
}

json cell_json(const CellSummary& c, const std::vector<EpisodeRecord>& records, const PaperNumbers& paper) {
  const double n = static_cast<double>(c.episodes);
  json seeds = json::array();
  for (const auto& s : c.per_seed)
    seeds.push_back({{"seed", s.seed}, {"episodes", s.episodes}, {"successes", s.successes}, {"rate", s.rate}});
  json flags = json::object();
  for (const auto& [name, count] : c.safety_flags)
    flags[name] = {{"episodes", count}, {"rate", static_cast<double>(count) / n}};
  json p = json::object();
  if (c.key.method.find('{') == std::string::npos) {
    std::set<std::string> quantities;
    for (const auto& e : paper.entries)
      if (e.kind == "cell" && e.variant.empty() && e.task == c.key.task && e.split == c.key.split && e.method == c.key.method)
        quantities.insert(e.quantity);
    for (const auto& q : quantities)
      if (const PaperNumber* e = find_paper_cell(paper, q, c.key.task, c.key.split, c.key.method, c.key.backbone))
        p[q] = e->entry;
  }
  return {{"task", c.key.task},
          {"split", c.key.split},
          {"method", c.key.method},
          {"method_base", method_base_name(c.key.method)},
          {"backbone", c.key.backbone},
          {"episodes", c.episodes},
          {"success_once", wilson_json(c.success_once)},
          {"success_at_end_rate", c.success_at_end_rate},
          {"per_seed", seeds},
          {"per_contract", per_contract_json(c.key, records)},
          {"mean_probe_steps", c.mean_probe_steps},
          {"mean_probe_displacement", c.mean_probe_displacement},
          {"safety",
           {{"episodes_with_flags", c.episodes_with_safety_flags},
            {"rate", static_cast<double>(c.episodes_with_safety_flags) / n},
            {"flags", flags}}},
          {"jobs", c.jobs},
          {"paper", p}};
}

// the rule of gates.cpp's promotion_verdict that decided (its order: prune, safety, seeds, promote, reject)
std::string deciding_rule(const PromotionVerdict& v) {
  if (v.decision == verdict_name(Verdict::kPrune)) return "one_seed_below_prune_floor";
  if (v.decision == verdict_name(Verdict::kExtendSeeds)) return "fewer_than_three_matched_seeds";
  if (v.decision == verdict_name(Verdict::kPromote)) return v.five_point_rule ? "five_point_gain" : "pareto_point";
  return v.safety_regression ? "safety_regression" : "no_five_point_gain_or_pareto_point";
}

// the verdict, the rule that decided it and its reason, then the fields every promotion JSON shares
json promotion_json(const PromotionVerdict& v) {
  json j = {{"verdict", v.decision}, {"rule", deciding_rule(v)}, {"reason", v.reason}};
  j.update(promotion_rule_fields(v));
  return j;
}

json comparison_json(const ComparisonPair& pair, const CellKey& ck, const CellKey& bk,
                     const std::vector<EpisodeRecord>& cand_all, const std::vector<EpisodeRecord>& base_all, const PaperNumbers& paper,
                     bool common_episodes) {
  const bool cross = pair.cross_backbone();
  const std::string cname = pair.candidate_side(), bname = pair.baseline_side();
  const std::string cell = ck.task + "/" + ck.split + (cross ? "" : "/" + ck.backbone) + ": " + cname + " vs " + bname;
  // pair exactly: the same (seed, contract, episode) on both sides, the same contract behind each
  std::map<PairKey, const EpisodeRecord*> c, b;
  for (const auto& r : cand_all) c.emplace(PairKey{r.seed, r.contract_index, r.episode_index}, &r);
  for (const auto& r : base_all) b.emplace(PairKey{r.seed, r.contract_index, r.episode_index}, &r);
  std::size_t only_c = 0, only_b = 0;
  std::optional<PairKey> first;
  const auto note_missing = [&](const PairKey& k, std::size_t& count) {
    ++count;
    if (!first || k < *first) first = k;
  };
  for (const auto& [k, r] : c)
    if (!b.count(k)) note_missing(k, only_c);
  for (const auto& [k, r] : b)
    if (!c.count(k)) note_missing(k, only_b);
  // --common-episodes: pair the episodes both cells hold (a job's first M episodes are the M-episode job's,
  // so a 50-episode cell pairs with the first 50 of a 200-episode one); the output says how many were left out
  std::vector<EpisodeRecord> cand, base;
  for (const auto& r : cand_all)
    if (!common_episodes || b.count(PairKey{r.seed, r.contract_index, r.episode_index})) cand.push_back(r);
  for (const auto& r : base_all)
    if (!common_episodes || c.count(PairKey{r.seed, r.contract_index, r.episode_index})) base.push_back(r);
  if (common_episodes) {
    std::erase_if(c, [&](const auto& e) { return !b.count(e.first); });
    std::erase_if(b, [&](const auto& e) { return !c.count(e.first); });
    if (c.empty()) throw InputError("results", cell, "the two cells hold no episode in common");
  }
  if (!common_episodes && (only_c || only_b))
    throw InputError("results", cell,
                     "the two cells hold different episodes: " + std::to_string(only_c) + " only in " + cname + ", " +
                         std::to_string(only_b) + " only in " + bname + " (first " + key_text(*first) +
                         "); run both on the same seeds and episode counts, or finish the incomplete job");
  std::vector<bool> cs, bs;
  std::map<std::uint64_t, std::tuple<std::int64_t, std::int64_t, std::int64_t>> per_seed;  // seed → (pairs, cand, base)
  for (const auto& [k, rc] : c) {
    const EpisodeRecord* rb = b.at(k);
    if (rc->contract_sha256 != rb->contract_sha256)
      throw InputError("results", cell, "episode " + key_text(k) + " ran different contracts (" + rc->contract_sha256.substr(0, 12) +
                                            " vs " + rb->contract_sha256.substr(0, 12) + ")");
    cs.push_back(rc->success_once);
    bs.push_back(rb->success_once);
    auto& [n, sc, sb] = per_seed[k.seed];
    ++n;
    sc += rc->success_once;
    sb += rb->success_once;
  }
  const BootstrapInterval d = paired_success_difference(cs, bs, 0.95, kBootstrapSamples, kBootstrapSeed);
  const bool excludes = d.lower > 0.0 || d.upper < 0.0;
  json seeds = json::array();
  for (const auto& [seed, t] : per_seed) {
    const auto& [n, sc, sb] = t;
    const double nn = static_cast<double>(n);
    seeds.push_back({{"seed", seed},
                     {"pairs", n},
                     {"candidate_rate", static_cast<double>(sc) / nn},
                     {"baseline_rate", static_cast<double>(sb) / nn},
                     {"difference", static_cast<double>(sc - sb) / nn}});
  }
  // the paper's difference, oriented candidate − baseline
  json paper_j = nullptr, agreement = nullptr;
  std::string agreement_reason;
  bool reversed = false;
  const bool suffixed = pair.candidate.find('{') != std::string::npos || pair.baseline.find('{') != std::string::npos;
  // a difference entry pairs two methods on one backbone: none is matched to a cross-backbone pair
  const PaperNumber* p = (!suffixed && !cross)
                             ? find_paper_difference(paper, ck.task, ck.split, pair.candidate, pair.baseline, ck.backbone, &reversed)
                             : nullptr;
  if (p == nullptr) {
    agreement_reason = suffixed ? "a label with a {...} suffix is not the paper's method"
                       : cross  ? "the paper has no difference between these two backbones in this cell (Table 4 prints "
                                  "ratios, no paired difference with an interval)"
                                : "the paper has no difference for this pair in this cell";
  } else {
    const double sign = reversed ? -1.0 : 1.0;
    json iv = nullptr;
    if (p->interval)
      iv = reversed ? json::array({-p->interval->second, -p->interval->first}) : json::array({p->interval->first, p->interval->second});
    paper_j = {{"value", sign * p->value},
               {"interval", iv},
               {"significant", p->significant ? json(*p->significant) : json(nullptr)},
               {"reversed", reversed},
               {"entry", p->entry}};
    if (!p->significant) {
      agreement_reason = "the paper gives no interval for this difference, so its significance is unknown";
      if (p->entry.contains("note")) agreement_reason += " (" + p->entry["note"].get<std::string>() + ")";
    } else if (!*p->significant) {
      agreement_reason = "the paper's difference is not significant (its 95 % interval includes 0)";
    } else if (!excludes) {
      agreement_reason = "our 95 % interval [" + fixed(d.lower, 4) + ", " + fixed(d.upper, 4) + "] includes 0";
    } else {
      const bool ours_positive = d.lower > 0.0;
      const bool paper_positive = sign * p->value > 0.0;
      agreement = ours_positive == paper_positive ? "same" : "different";
    }
  }
  PromotionVerdict v;
  try {
    v = promotion_verdict(cand, base, kBootstrapSamples, kBootstrapSeed);
  } catch (const InputError& e) {
    throw InputError("results", cell, e.reason());
  }
  return {{"candidate", pair.candidate},
          {"baseline", pair.baseline},
          {"task", ck.task},
          {"split", ck.split},
          {"backbone", cross ? json(nullptr) : json(ck.backbone)},
          {"candidate_backbone", ck.backbone},
          {"baseline_backbone", bk.backbone},
          {"pairs", cs.size()},
          {"unpaired", common_episodes ? json({{"candidate", only_c}, {"baseline", only_b}}) : json(nullptr)},
          {"seeds", per_seed.size()},
          {"candidate_success", v.candidate_rate},
          {"baseline_success", v.baseline_rate},
          {"difference",
           {{"estimate", d.estimate},
            {"lower", d.lower},
            {"upper", d.upper},
            {"confidence", d.confidence},
            {"samples", d.samples},
            {"seed", d.seed},
            {"excludes_zero", excludes}}},
          {"per_seed", seeds},
          {"paper", paper_j},
          {"sign_agreement", agreement},
          {"sign_agreement_reason", agreement.is_null() ? json(agreement_reason) : json(nullptr)},
          {"promotion", promotion_json(v)}};
}

}  // namespace

std::string method_base_name(std::string_view label) { return std::string(label.substr(0, label.find('{'))); }

std::string ComparisonPair::candidate_side() const {
  return candidate_backbone.empty() ? candidate : candidate + "@" + candidate_backbone;
}
std::string ComparisonPair::baseline_side() const {
  return baseline_backbone.empty() ? baseline : baseline + "@" + baseline_backbone;
}
std::string ComparisonPair::text() const { return candidate_side() + " vs " + baseline_side(); }

namespace {
// `LABEL` or `LABEL@BACKBONE`: the first '@' outside the label's {...} separates
std::pair<std::string, std::string> split_side(std::string_view side) {
  int depth = 0;
  for (std::size_t i = 0; i < side.size(); ++i) {
    if (side[i] == '{') ++depth;
    else if (side[i] == '}') depth = std::max(0, depth - 1);
    else if (side[i] == '@' && depth == 0)
      return {std::string(trim(side.substr(0, i))), std::string(trim(side.substr(i + 1)))};
  }
  return {std::string(side), {}};
}
}  // namespace

ComparisonPair parse_comparison_pair(std::string_view text, const std::string& source, const std::string& field) {
  static constexpr std::string_view kSep = " vs ";
  const std::size_t at = text.find(kSep);
  if (at == std::string_view::npos)
    throw InputError(source, field, "expected 'CANDIDATE vs BASELINE' (got " + quote_input(text) + ")");
  if (text.find(kSep, at + 1) != std::string_view::npos)
    throw InputError(source, field, "more than one ' vs ' in " + quote_input(text));
  const std::string_view cand = trim(text.substr(0, at)), base = trim(text.substr(at + kSep.size()));
  ComparisonPair p;
  std::tie(p.candidate, p.candidate_backbone) = split_side(cand);
  std::tie(p.baseline, p.baseline_backbone) = split_side(base);
  if (p.candidate.empty() || p.baseline.empty())
    throw InputError(source, field, "empty method label in " + quote_input(text));
  const bool c_at = split_side(cand).first.size() != cand.size(), b_at = split_side(base).first.size() != base.size();
  if (c_at != b_at)
    throw InputError(source, field, "name a backbone on both sides ('LABEL@BACKBONE vs LABEL@BACKBONE') or on neither (got " +
                                        quote_input(text) + ")");
  if (c_at && (p.candidate_backbone.empty() || p.baseline_backbone.empty()))
    throw InputError(source, field, "empty backbone after '@' in " + quote_input(text));
  if (p.candidate == p.baseline && p.candidate_backbone == p.baseline_backbone)
    throw InputError(source, field, "the candidate and the baseline are the same " + std::string(c_at ? "cell " : "label ") +
                                        quote_input(p.candidate_side()));
  return p;
}

std::vector<ComparisonPair> parse_pairs_text(std::string_view text, const std::string& source) {
  std::vector<ComparisonPair> out;
  std::size_t line_no = 0;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    const std::string_view line = trim(text.substr(0, nl));
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    if (line.empty() || line.front() == '#') continue;
    out.push_back(parse_comparison_pair(line, source + ":" + std::to_string(line_no), "pair"));
  }
  return out;
}

PaperNumbers parse_paper_numbers(std::string_view text, const std::string& source) {
  const json j = parse_json_input(text, source);
  if (!j.is_object()) throw InputError(source, "", "must be a JSON object with \"schema_version\" and \"entries\"");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "schema_version" && it.key() != "description" && it.key() != "entries")
      throw InputError(source, it.key(), "unknown key (expected schema_version, description, entries)");
  if (!j.contains("schema_version") || !j["schema_version"].is_string() || j["schema_version"].get<std::string>() != kPaperNumbersSchemaVersion)
    throw InputError(source, "schema_version", "must be \"" + std::string(kPaperNumbersSchemaVersion) + "\"");
  if (!j.contains("entries") || !j["entries"].is_array() || j["entries"].empty())
    throw InputError(source, "entries", "must be a non-empty array");
  PaperNumbers out;
  out.source = source;
  std::set<std::string> ids;
  std::map<std::string, std::vector<std::size_t>> scopes;  // match key → entries sharing it
  for (std::size_t i = 0; i < j["entries"].size(); ++i) {
    PaperNumber p = parse_entry(j["entries"][i], source, i);
    if (!ids.insert(p.id).second)
      throw InputError(source, "entries[" + std::to_string(i) + "].id", "duplicate id " + quote_input(p.id, '"'));
    if (const std::string k = match_key(p); !k.empty()) {
      for (const std::size_t other : scopes[k]) {
        const PaperNumber& q = out.entries[other];
        bool overlap = p.backbones.empty() && q.backbones.empty();
        for (const auto& bb : p.backbones)
          overlap = overlap || std::find(q.backbones.begin(), q.backbones.end(), bb) != q.backbones.end();
        if (overlap)
          throw InputError(source, "entries[" + std::to_string(i) + "]",
                           "matches the same cell or pair as " + quote_input(q.id, '"') +
                               " for the same backbones; give one a \"variant\" or disjoint \"backbones\"");
      }
      scopes[k].push_back(out.entries.size());
    }
    out.entries.push_back(std::move(p));
  }
  return out;
}

PaperNumbers builtin_paper_numbers() {
  return parse_paper_numbers(data::builtin_paper_numbers_text(), "built-in configs/paper/numbers.json");
}

const PaperNumber* find_paper_cell(const PaperNumbers& paper, std::string_view quantity, std::string_view task,
                                   std::string_view split, std::string_view method, std::string_view backbone) {
  if (method.find('{') != std::string_view::npos) return nullptr;
  std::vector<const PaperNumber*> candidates;
  for (const auto& e : paper.entries)
    if (e.kind == "cell" && e.variant.empty() && e.quantity == quantity && e.task == task && e.split == split && e.method == method)
      candidates.push_back(&e);
  return most_specific(candidates, backbone);
}

const PaperNumber* find_paper_difference(const PaperNumbers& paper, std::string_view task, std::string_view split,
                                         std::string_view candidate, std::string_view baseline, std::string_view backbone,
                                         bool* reversed) {
  if (candidate.find('{') != std::string_view::npos || baseline.find('{') != std::string_view::npos) return nullptr;
  std::vector<const PaperNumber*> forward, backward;
  for (const auto& e : paper.entries) {
    if (e.kind != "difference" || !e.variant.empty() || e.quantity != "success_difference" || e.task != task || e.split != split)
      continue;
    if (e.candidate == candidate && e.baseline == baseline) forward.push_back(&e);
    if (e.candidate == baseline && e.baseline == candidate) backward.push_back(&e);
  }
  if (const PaperNumber* p = most_specific(forward, backbone)) {
    if (reversed) *reversed = false;
    return p;
  }
  const PaperNumber* p = most_specific(backward, backbone);
  if (p && reversed) *reversed = true;
  return p;
}

namespace {
// ---- backbone as a random effect

// the paired differences of one backbone's two cells, by seed and block (episodes sharing an initial state)
std::vector<std::vector<std::vector<double>>> clustered_differences(const std::vector<EpisodeRecord>& cand,
                                                                    const std::vector<EpisodeRecord>& base) {
  std::map<PairKey, const EpisodeRecord*> b;
  for (const auto& r : base) b.emplace(PairKey{r.seed, r.contract_index, r.episode_index}, &r);
  std::set<std::int64_t> contracts;
  for (const auto& r : cand) contracts.insert(r.contract_index);
  const auto n = static_cast<std::int64_t>(contracts.size());
  std::map<std::uint64_t, std::map<std::int64_t, std::vector<double>>> by_seed;  // seed → block → differences
  for (const auto& r : cand) {
    const auto it = b.find(PairKey{r.seed, r.contract_index, r.episode_index});
    if (it == b.end()) continue;  // an unpaired episode (--common-episodes; otherwise the pair was refused)
    by_seed[r.seed][r.episode_index / n].push_back(static_cast<double>(static_cast<int>(r.success_once) -
                                                                       static_cast<int>(it->second->success_once)));
  }
  std::vector<std::vector<std::vector<double>>> out;
  for (auto& [seed, blocks] : by_seed) {
    out.emplace_back();
    for (auto& [block, d] : blocks) out.back().push_back(std::move(d));
  }
  return out;
}

int direction(const BootstrapInterval& d) { return d.lower > 0.0 ? 1 : d.upper < 0.0 ? -1 : 0; }
const char* direction_name(int d) { return d > 0 ? "positive" : d < 0 ? "negative" : "none"; }

json interval_json(const BootstrapInterval& d) {
  return {{"estimate", d.estimate}, {"lower", d.lower},     {"upper", d.upper},
          {"confidence", d.confidence}, {"samples", d.samples}, {"seed", d.seed},
          {"pairs", d.pairs}, {"direction", direction_name(direction(d))}};
}

json across_backbones_json(const ComparisonPair& pair, const std::string& task, const std::string& split,
                           const std::vector<std::pair<std::string, std::pair<const std::vector<EpisodeRecord>*,
                                                                              const std::vector<EpisodeRecord>*>>>& cells) {
  ClusteredValues all;
  json per = json::array();
  std::vector<int> dirs;
  std::vector<std::string> names;
  for (const auto& [backbone, two] : cells) {
    auto clustered = clustered_differences(*two.first, *two.second);
    if (clustered.empty()) throw InputError("results", task + "/" + split + "/" + backbone, "the two cells hold no episode in common");
    const BootstrapInterval d = hierarchical_bootstrap({clustered}, 0.95, kBootstrapSamples, kBootstrapSeed);
    per.push_back({{"backbone", backbone}, {"seeds", clustered.size()}, {"difference", interval_json(d)}});
    dirs.push_back(direction(d));
    names.push_back(backbone);
    all.push_back(std::move(clustered));
  }
  const BootstrapInterval pooled = hierarchical_bootstrap(all, 0.95, kBootstrapSamples, kBootstrapSeed);
  const int pd = direction(pooled);
  const bool any_pos = std::count(dirs.begin(), dirs.end(), 1) > 0, any_neg = std::count(dirs.begin(), dirs.end(), -1) > 0;
  std::string verdict, reason;
  const auto list = [&](auto pred) {
    std::string t;
    for (std::size_t i = 0; i < dirs.size(); ++i)
      if (pred(dirs[i])) t += (t.empty() ? "" : ", ") + names[i];
    return t;
  };
  if (any_pos && any_neg) {
    verdict = "depends_on_backbone";
    reason = "positive on " + list([](int d) { return d > 0; }) + ", negative on " + list([](int d) { return d < 0; });
  } else if (pd != 0 && std::all_of(dirs.begin(), dirs.end(), [&](int d) { return d == pd; })) {
    verdict = "holds_on_every_backbone";
    reason = std::string("the pooled interval and each of the ") + std::to_string(dirs.size()) + " backbones' exclude 0 (" +
             direction_name(pd) + ")";
  } else if (pd != 0) {
    verdict = "holds_on_average";
    reason = std::string("the pooled interval excludes 0 (") + direction_name(pd) + "); not shown on " +
             list([](int d) { return d == 0; });
  } else if (any_pos || any_neg) {
    verdict = "depends_on_backbone";
    reason = "the pooled interval includes 0; shown (" + std::string(direction_name(any_pos ? 1 : -1)) + ") on " +
             list([](int d) { return d != 0; }) + " only";
  } else {
    verdict = "not_shown";
    reason = "no backbone's interval and not the pooled one excludes 0";
  }
  return {{"candidate", pair.candidate}, {"baseline", pair.baseline}, {"task", task}, {"split", split},
          {"backbones", per},           {"pooled", interval_json(pooled)},
          {"verdict", verdict},         {"verdict_reason", reason}};
}

}  // namespace

json compare_records(const std::vector<EpisodeRecord>& records, const std::vector<ComparisonPair>& pairs,
                     const PaperNumbers& paper, const CompareInputs& inputs, bool common_episodes, bool across_backbones) {
  {
    std::set<std::string> seen;
    for (const auto& p : pairs)
      if (!seen.insert(p.text()).second) throw InputError("compare", "pair '" + p.text() + "'", "given twice");
  }
  const std::vector<CellSummary> cells = summarize_records(records);
  std::map<CellKey, std::vector<EpisodeRecord>> by_cell;
  for (const auto& r : records) by_cell[cell_key(r)].push_back(r);

  json dirs = json::array();
  for (const auto& d : inputs.directories)
    dirs.push_back({{"dir", d.dir}, {"files", d.files}, {"records", d.records}, {"notes", d.notes}});
  json out = {{"schema_version", kComparisonSchemaVersion},
              {"inputs",
               {{"results_dirs", dirs},
                {"records", records.size()},
                {"paper", {{"source", paper.source}, {"entries", paper.entries.size()}}}}},
              {"bootstrap", {{"samples", kBootstrapSamples}, {"seed", kBootstrapSeed}, {"confidence", 0.95}}},
              {"cells", json::array()},
              {"pairs", json::array()},
              {"comparisons", json::array()}};
  for (const auto& c : cells) out["cells"].push_back(cell_json(c, by_cell.at(c.key), paper));

  // (task, split, backbone) → label → cell key
  std::map<std::tuple<std::string, std::string, std::string>, std::map<std::string, CellKey>> groups;
  std::set<std::string> labels, label_backbones;
  std::set<std::pair<std::string, std::string>> task_splits;
  for (const auto& c : cells) {
    groups[{c.key.task, c.key.split, c.key.backbone}][c.key.method] = c.key;
    labels.insert(c.key.method);
    label_backbones.insert(c.key.method + "@" + c.key.backbone);
    task_splits.emplace(c.key.task, c.key.split);
  }
  for (const auto& pair : pairs) {
    json one_sided = json::array();
    std::size_t compared = 0;
    if (pair.cross_backbone()) {
      for (const auto& [task, split] : task_splits) {
        const CellKey ck{task, split, pair.candidate, pair.candidate_backbone}, bk{task, split, pair.baseline, pair.baseline_backbone};
        const bool has_c = by_cell.count(ck) > 0, has_b = by_cell.count(bk) > 0;
        if (!has_c && !has_b) continue;
        if (!has_c || !has_b) {
          one_sided.push_back({{"task", task}, {"split", split}, {"backbone", has_c ? ck.backbone : bk.backbone},
                               {"present", has_c ? pair.candidate_side() : pair.baseline_side()}});
          continue;
        }
        out["comparisons"].push_back(comparison_json(pair, ck, bk, by_cell.at(ck), by_cell.at(bk), paper, common_episodes));
        ++compared;
      }
      if (compared == 0) {
        std::string present;
        for (const auto& l : label_backbones) present += (present.empty() ? "" : ", ") + l;
        throw InputError("compare", "pair '" + pair.text() + "'",
                         "no (task, split) holds both cells (cells in the results: " + present + ")");
      }
    }
    for (const auto& [g, by_label] : groups) {
      if (pair.cross_backbone()) break;
      const auto ci = by_label.find(pair.candidate), bi = by_label.find(pair.baseline);
      if (ci == by_label.end() && bi == by_label.end()) continue;
      const auto& [task, split, backbone] = g;
      if (ci == by_label.end() || bi == by_label.end()) {
        one_sided.push_back({{"task", task}, {"split", split}, {"backbone", backbone},
                             {"present", ci != by_label.end() ? pair.candidate : pair.baseline}});
        continue;
      }
      out["comparisons"].push_back(
          comparison_json(pair, ci->second, bi->second, by_cell.at(ci->second), by_cell.at(bi->second), paper, common_episodes));
      ++compared;
    }
    if (compared == 0 && !pair.cross_backbone()) {
      std::string present;
      for (const auto& l : labels) present += (present.empty() ? "" : ", ") + l;
      throw InputError("compare", "pair '" + pair.candidate + " vs " + pair.baseline + "'",
                       "no (task, split, backbone) holds both labels (labels in the results: " + present + ")");
    }
    out["pairs"].push_back({{"candidate", pair.candidate},
                            {"baseline", pair.baseline},
                            {"candidate_backbone", pair.cross_backbone() ? json(pair.candidate_backbone) : json(nullptr)},
                            {"baseline_backbone", pair.cross_backbone() ? json(pair.baseline_backbone) : json(nullptr)},
                            {"cells_compared", compared},
                            {"cells_with_one_side", one_sided}});
  }
  if (across_backbones) {
    out["across_backbones"] = json::array();
    for (const auto& pair : pairs) {
      if (pair.cross_backbone()) continue;
      std::map<std::pair<std::string, std::string>,
               std::vector<std::pair<std::string, std::pair<const std::vector<EpisodeRecord>*, const std::vector<EpisodeRecord>*>>>>
          by_task_split;
      for (const auto& [g, by_label] : groups) {
        const auto ci = by_label.find(pair.candidate), bi = by_label.find(pair.baseline);
        if (ci == by_label.end() || bi == by_label.end()) continue;
        const auto& [task, split, backbone] = g;
        by_task_split[{task, split}].push_back({backbone, {&by_cell.at(ci->second), &by_cell.at(bi->second)}});
      }
      for (const auto& [ts, cells_of] : by_task_split)
        if (cells_of.size() >= 2) out["across_backbones"].push_back(across_backbones_json(pair, ts.first, ts.second, cells_of));
    }
  }
  return out;
}

json compare_directories(const std::vector<std::string>& dirs, const std::vector<ComparisonPair>& pairs,
                         const PaperNumbers& paper, bool common_episodes, bool across_backbones) {
  namespace fs = std::filesystem;
  if (dirs.empty()) throw InputError("compare", "RESULTS_DIR", "give at least one results directory");
  CompareInputs inputs;
  std::vector<EpisodeRecord> records;
  std::map<std::string, std::string> canonical;  // canonical path → as given
  for (const auto& d : dirs) {
    std::error_code ec;
    const std::string c = fs::weakly_canonical(fs::path(d), ec).string();
    if (!ec) {
      if (const auto [it, fresh] = canonical.emplace(c, d); !fresh)
        throw InputError(d, "", "given twice (also as " + it->second + ")");
    }
    ResultSet rs = load_results(d);
    if (rs.records.empty()) throw InputError(d, "", no_records_reason(rs));
    inputs.directories.push_back({d, rs.files, rs.records.size(), rs.notes});
    records.insert(records.end(), std::make_move_iterator(rs.records.begin()), std::make_move_iterator(rs.records.end()));
  }
  return compare_records(records, pairs, paper, inputs, common_episodes, across_backbones);
}

}  // namespace actionshift::eval
