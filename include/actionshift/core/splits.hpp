#pragma once
/// \file Seeded split and pool generators (generator "grammar-v1"; rules in docs/splits.md) and
/// the reference's frozen manifests. generate(rule, seed) is a pure function: validate() re-runs
/// it and compares the result with the file byte for byte.

#include "actionshift/core/grammar.hpp"
#include "actionshift/core/manifest.hpp"
#include "actionshift/core/reference_contracts.hpp"

#include <array>
#include <functional>
#include <set>
#include <string>
#include <vector>

namespace actionshift::splits {

inline constexpr int kTestSize = 32;     ///< evaluation contracts per generated split
inline constexpr int kTrainSize = 64;    ///< training contracts per generated split (32 for unseen_composition)
inline constexpr int kFullPoolSize = 180;  ///< identity + 5 × 32 split contracts + 19 distractors
inline constexpr std::array<double, 2> kHeldOutScales{0.5, 2.0};  ///< unseen_value's held-out scale values
inline constexpr int kIdentifierTrainSize = 96;    ///< identifier_training: contracts the identifiers are trained on
inline constexpr int kIdentifierHeldOutSize = 12;  ///< identifier_training: held-out contracts for field accuracy

/// Generated splits, in the order the full pool lists them.
inline const std::vector<std::string>& generated_split_rules() {
  static const std::vector<std::string> r{"seen", "unseen_value", "unseen_composition", "long_lag", "task_transfer"};
  return r;
}
/// The reference's frozen splits (two contracts each; docs/reference.md, *Contracts*).
inline const std::vector<std::string>& reference_split_rules() {
  static const std::vector<std::string> r{"reference_seen", "reference_unseen_composition", "reference_long_lag"};
  return r;
}
/// Every rule generate() knows, splits first, then pools.
inline std::vector<std::string> all_rules() {
  std::vector<std::string> r = generated_split_rules();
  for (const auto& s : reference_split_rules()) r.push_back(s);
  r.push_back("reference9");
  r.push_back("full");
  r.push_back("identifier_training");
  return r;
}

/// The rules whose contracts are evaluated (every rule but the identifiers' training distribution).
inline std::vector<std::string> evaluation_rules() {
  std::vector<std::string> r = all_rules();
  r.erase(std::find(r.begin(), r.end(), "identifier_training"));
  return r;
}

namespace detail {

/// A rule's own random stream: the seed mixed with the rule name's hash.
inline Rng rule_rng(const std::string& rule, std::uint64_t seed) {
  const auto d = sha256_bytes(rule);
  std::uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | d[static_cast<std::size_t>(i)];
  return Rng(derive_seed({seed, h}));
}

/// Draws `n` distinct contracts accepted by `keep` and not in `taken` (hashes), adding them to `taken`.
inline std::vector<Contract> draw(int n, Rng& rng, const std::function<Contract(Rng&)>& gen,
                                  const std::function<bool(const Contract&)>& keep, std::set<std::string>& taken) {
  std::vector<Contract> out;
  for (int attempts = 0; static_cast<int>(out.size()) < n; ++attempts) {
    if (attempts > 100000) throw std::runtime_error("split generator: could not draw enough distinct contracts");
    Contract c = gen(rng);
    if (!keep(c)) continue;
    if (!taken.insert(c.sha256()).second) continue;
    out.push_back(c);
  }
  return out;
}

inline void sort_by_hash(std::vector<Contract>& v) {
  std::sort(v.begin(), v.end(), [](const Contract& a, const Contract& b) { return a.sha256() < b.sha256(); });
}

inline bool has_held_out_scale(const Contract& c) {
  for (double s : c.scale())
    for (double h : kHeldOutScales)
      if (s == h) return true;
  return false;
}

/// unseen_composition test contracts: a random subset of ≥ 3 of the six non-lag fields, each set
/// to a random non-identity value; lag 0.
inline Contract composition_sample(Rng& rng) {
  static const std::array<const char*, 6> kFields{"permutation", "sign", "scale", "target", "frame", "gripper"};
  std::array<bool, 6> on{};
  int count = 0;
  while (count < 3) {
    count = 0;
    for (auto& b : on) count += (b = rng.coin());
  }
  ContractFields f;
  const Contract id;
  if (on[0])
    do rng.shuffle(f.permutation);
    while (std::equal(f.permutation.begin(), f.permutation.end(), id.permutation().begin()));
  if (on[1])
    do
      for (auto& s : f.sign) s = rng.coin() ? -1 : 1;
    while (std::all_of(f.sign.begin(), f.sign.end(), [](long long s) { return s == 1; }));
  if (on[2])
    do
      for (auto& s : f.scale) s = grammar::kScaleGrid[rng.uniform_int(grammar::kScaleGrid.size())];
    while (std::all_of(f.scale.begin(), f.scale.end(), [](double s) { return s == 1.0; }));
  if (on[3]) f.target = "absolute";
  if (on[4]) f.frame = "tool";
  if (on[5]) f.gripper_inverted = true;
  (void)kFields;
  return Contract::make(f);
}

/// unseen_composition training contracts: identity, then single-field changes cycling through
/// permutation, sign, scale, target, frame, gripper.
inline std::vector<Contract> single_field_contracts(int n, Rng& rng, std::set<std::string>& taken) {
  std::vector<Contract> out{Contract::identity()};
  taken.insert(out.back().sha256());
  for (int k = 0; static_cast<int>(out.size()) < n; ++k) {
    if (k > 100000) throw std::runtime_error("split generator: could not draw single-field contracts");
    ContractFields f;
    switch (k % 6) {
      case 0: rng.shuffle(f.permutation); break;
      case 1: for (auto& s : f.sign) s = rng.coin() ? -1 : 1; break;
      case 2: for (auto& s : f.scale) s = grammar::kScaleGrid[rng.uniform_int(grammar::kScaleGrid.size())]; break;
      case 3: f.target = "absolute"; break;
      case 4: f.frame = "tool"; break;
      default: f.gripper_inverted = true; break;
    }
    const Contract c = Contract::make(f);
    if (c.composition_signature().size() != 1) continue;
    if (!taken.insert(c.sha256()).second) continue;
    out.push_back(c);
  }
  return out;
}

}  // namespace detail

/// Generates the manifest for `rule` with `seed`. Throws std::invalid_argument for an unknown rule.
inline Manifest generate(const std::string& rule, std::uint64_t seed = kDefaultSeed) {
  using grammar::SamplerSpec;
  auto any = [](const Contract&) { return true; };
  auto breaking = [](const Contract& c) { return grammar::is_breaking(c); };
  Rng rng = detail::rule_rng(rule, seed);
  std::set<std::string> taken;

  // seen / task_transfer: one distribution for train and test (delta, base, lag 0; permutation,
  // sign, per-channel scale and gripper random); test is hash-disjoint from train.
  auto seen_like = [&](const std::string& name, const std::string& description, nlohmann::json meta) {
    SamplerSpec s;
    auto gen = [&](Rng& r) { return grammar::sample(s, r); };
    auto train = detail::draw(kTrainSize, rng, gen, breaking, taken);
    std::set<std::vector<std::string>> train_signatures;
    for (const auto& c : train) train_signatures.insert(c.composition_signature());
    auto seen_signature = [&](const Contract& c) {
      return grammar::is_breaking(c) && train_signatures.count(c.composition_signature()) > 0;
    };
    auto test = detail::draw(kTestSize, rng, gen, seen_signature, taken);
    detail::sort_by_hash(train);
    detail::sort_by_hash(test);
    return Manifest::split(name, rule, seed, description, std::move(meta), train, test);
  };

  if (rule == "seen")
    return seen_like("seen",
                     "test contracts drawn from the training distribution (random permutation, sign, grid scale, "
                     "gripper; delta, base, lag 0), hash-disjoint from train",
                     nlohmann::json::object());
  if (rule == "task_transfer")
    return seen_like("task_transfer",
                     "seen-style contracts; adapters are fitted on the train tasks and evaluated on the test tasks",
                     {{"train_tasks", {"pick_cube", "push_cube"}}, {"test_tasks", {"pull_cube", "stack_cube"}}});
  if (rule == "unseen_value") {
    SamplerSpec train_spec;
    train_spec.scales = {0.6, 0.75, 1.0, 1.25, 1.5};
    SamplerSpec test_spec;
    auto train = detail::draw(kTrainSize, rng, [&](Rng& r) { return grammar::sample(train_spec, r); }, breaking, taken);
    auto test = detail::draw(kTestSize, rng, [&](Rng& r) { return grammar::sample(test_spec, r); },
                             [](const Contract& c) { return grammar::is_breaking(c) && detail::has_held_out_scale(c); },
                             taken);
    detail::sort_by_hash(train);
    detail::sort_by_hash(test);
    return Manifest::split("unseen_value", rule, seed,
                           "scale values 0.5 and 2.0 never occur in train; every test contract uses at least one",
                           {{"held_out_scales", {0.5, 2.0}}}, train, test);
  }
  if (rule == "unseen_composition") {
    auto train = detail::single_field_contracts(kTestSize, rng, taken);
    auto test = detail::draw(kTestSize, rng, detail::composition_sample, breaking, taken);
    detail::sort_by_hash(train);
    detail::sort_by_hash(test);
    return Manifest::split("unseen_composition", rule, seed,
                           "train changes at most one field from identity; test changes at least three "
                           "(lag 0), so composition signatures are disjoint",
                           {{"train_max_signature", 1}, {"test_min_signature", 3}}, train, test);
  }
  if (rule == "long_lag") {
    SamplerSpec train_spec;
    train_spec.lags = {0, 1};
    SamplerSpec test_spec;
    test_spec.lags = {2, 4};
    auto train = detail::draw(kTrainSize, rng, [&](Rng& r) { return grammar::sample(train_spec, r); }, breaking, taken);
    auto test = detail::draw(kTestSize, rng, [&](Rng& r) { return grammar::sample(test_spec, r); }, breaking, taken);
    detail::sort_by_hash(train);
    detail::sort_by_hash(test);
    return Manifest::split("long_lag", rule, seed, "train lags {0, 1}; test lags {2, 4}",
                           {{"train_lags", {0, 1}}, {"test_lags", {2, 4}}}, train, test);
  }
  if (rule == "reference_seen" || rule == "reference_unseen_composition" || rule == "reference_long_lag") {
    const std::string which = rule.substr(std::string("reference_").size());
    // the descriptions are part of the committed manifests' content hashes, so they keep the words
    // they were generated with ("\u00a7" is the section sign: the reference write-up's section 2.6 and
    // section 3, today docs/reference.md, *Contracts*); changing them would change every job id
    return Manifest::split(rule, rule, seed,
                           "the reference implementation's two frozen 6-DoF contracts for its '" + which +
                               "' split (reference \u00a72.6), in its contract-index order",
                           nlohmann::json::object(), {}, reference::representative_contracts(which));
  }
  if (rule == "reference9")
    return Manifest::pool("reference9", rule, seed,
                          "the reference's declared nine-contract pool, in its order (reference \u00a73)",
                          nlohmann::json::object(), reference::pool9());
  if (rule == "full") {
    std::vector<Contract> members{Contract::identity()};
    std::set<std::string> in_pool{members[0].sha256()};
    std::set<std::string> all_generated{members[0].sha256()};
    for (const auto& r : generated_split_rules()) {
      const Manifest m = generate(r, seed);
      for (const auto& rec : m.train()) all_generated.insert(rec.sha256);
      for (const auto& rec : m.test()) {
        all_generated.insert(rec.sha256);
        if (in_pool.insert(rec.sha256).second) members.push_back(rec.contract);
      }
    }
    for (const auto& c : reference::pool9()) all_generated.insert(c.sha256());
    // distractors: anywhere in the grammar, hash-disjoint from every split and the reference pool
    SamplerSpec d;
    d.targets = {"delta", "absolute"};
    d.frames = {"base", "tool"};
    d.lags = {0, 1, 2, 4};
    const int n_distractors = kFullPoolSize - static_cast<int>(members.size());
    auto distractors = detail::draw(n_distractors, rng, [&](Rng& r) { return grammar::sample(d, r); }, any, all_generated);
    for (const auto& c : distractors) members.push_back(c);
    return Manifest::pool("full", rule, seed,
                          "identity, every test contract of the five generated splits (in split order), then "
                          "distractors drawn from the whole grammar",
                          {{"distractors", n_distractors}}, members);
  }
  if (rule == "identifier_training") {
    // the learned identifiers' training distribution (the public reference implementation's
    // training-contract sampler, on the grammar grids): every field uniform over the whole grammar,
    // hash-rejected against every contract of every other manifest generated with the same seed
    // (train, test and pool members), so no identifier is ever trained on a contract it is evaluated on
    std::set<std::string> excluded;
    for (const auto& r : evaluation_rules()) {
      const Manifest m = generate(r, seed);
      for (const auto* list : {&m.train(), &m.test()})
        for (const auto& rec : *list) excluded.insert(rec.sha256);
    }
    SamplerSpec s;
    s.targets = {"delta", "absolute"};
    s.frames = {"base", "tool"};
    s.lags = {0, 1, 2, 4};
    auto gen = [&](Rng& r) { return grammar::sample(s, r); };
    auto train = detail::draw(kIdentifierTrainSize, rng, gen, any, excluded);
    auto held_out = detail::draw(kIdentifierHeldOutSize, rng, gen, any, excluded);
    detail::sort_by_hash(train);
    detail::sort_by_hash(held_out);
    return Manifest::split("identifier_training", rule, seed,
                           "training contracts of the learned identifiers (train) and held-out contracts for their field "
                           "accuracy (test): every field uniform over the grammar grids, hash-rejected against every "
                           "contract of every other manifest of the same seed",
                           {{"excluded_rules", evaluation_rules()}}, train, held_out);
  }
  throw std::invalid_argument("unknown split rule: " + rule);
}

}  // namespace actionshift::splits
