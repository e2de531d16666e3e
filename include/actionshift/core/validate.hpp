#pragma once
/// \file Manifest validation: hashes, grammar coverage, the split rules' disjointness, and
/// regeneration from (rule, seed). One Check per line of `actionshift validate`.

#include "actionshift/core/grammar.hpp"
#include "actionshift/core/manifest.hpp"
#include "actionshift/core/splits.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace actionshift {

/// The outcome of one named check.
struct Check {
  std::string name;    ///< e.g. "manifest_hash"
  bool ok{false};
  std::string detail;  ///< what was found (the hash, a count, or the first failure)
};

namespace detail {
inline std::string join(const std::vector<std::string>& v, const char* sep = ",") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}
inline std::set<std::string> field_values(const std::vector<ManifestRecord>& recs, const std::string& field) {
  std::set<std::string> out;
  for (const auto& r : recs) {
    const nlohmann::json j = r.contract.to_json_value();
    if (field == "scale" || field == "sign" || field == "permutation") {  // list fields: their elements
      for (const auto& v : j[field]) out.insert(canonical_dump(v));
    } else {
      out.insert(canonical_dump(j[field]));
    }
  }
  return out;
}
}  // namespace detail

/// All checks for one manifest on its own. `regenerate` re-runs the generator for known rules.
inline std::vector<Check> validate(const Manifest& m, bool regenerate = true) {
  std::vector<Check> out;
  auto add = [&](std::string name, bool ok, std::string detail) { out.push_back({std::move(name), ok, std::move(detail)}); };
  const auto& train = m.train();
  const auto& test = m.test();

  // record hashes and signatures
  {
    std::string bad;
    for (std::size_t i = 0; i < train.size() + test.size() && bad.empty(); ++i) {
      const bool is_train = i < train.size();
      const auto& r = is_train ? train[i] : test[i - train.size()];
      const std::string where = std::string(is_train ? "train" : (m.is_pool() ? "members" : "test")) + "[" +
                                std::to_string(is_train ? i : i - train.size()) + "]";
      if (r.sha256 != r.contract.sha256()) bad = where + " sha256 does not match its contract";
      else if (r.composition != r.contract.composition_signature()) bad = where + " composition does not match its contract";
    }
    add("record_hashes", bad.empty(), bad.empty() ? std::to_string(train.size() + test.size()) + " records" : bad);
  }
  const std::string h = m.computed_sha256();
  add("manifest_hash", h == m.manifest_sha256(),
      h == m.manifest_sha256() ? h : "stored " + m.manifest_sha256() + " != computed " + h);
  if (m.is_pool()) {
    const std::string p = m.pool_sha256();
    add("pool_hash", p == m.stored_pool_sha256(), p == m.stored_pool_sha256() ? p : "stored " + m.stored_pool_sha256() + " != computed " + p);
  }
  {
    std::string bad;
    for (const auto* list : {&train, &test})
      for (const auto& r : *list) {
        auto v = grammar::violations(r.contract);
        if (!v.empty() && bad.empty()) bad = r.sha256.substr(0, 12) + ": " + v.front();
      }
    add("grammar_coverage", bad.empty(), bad.empty() ? "every contract on the grammar grids" : bad);
  }
  {
    std::set<std::string> seen;
    std::string dup;
    for (const auto* list : {&train, &test})
      for (const auto& r : *list)
        if (!seen.insert(r.contract.sha256()).second && dup.empty()) dup = r.contract.sha256().substr(0, 12);
    add(m.is_pool() ? "unique_members" : "disjoint_contracts", dup.empty(),
        dup.empty() ? (m.is_pool() ? std::to_string(test.size()) + " distinct members" : "train and test share no contract")
                    : "contract " + dup + " appears twice");
  }

  const std::string& rule = m.rule();
  const auto& gen = splits::generated_split_rules();
  const bool generated = std::find(gen.begin(), gen.end(), rule) != gen.end();
  if (generated) {
    add("min_contracts", test.size() >= static_cast<std::size_t>(splits::kTestSize),
        std::to_string(test.size()) + " test contracts (need >= " + std::to_string(splits::kTestSize) + ")");
    const bool sorted = std::is_sorted(test.begin(), test.end(), [](auto& a, auto& b) { return a.sha256 < b.sha256; }) &&
                        std::is_sorted(train.begin(), train.end(), [](auto& a, auto& b) { return a.sha256 < b.sha256; });
    add("ordering", sorted, sorted ? "train and test sorted by sha256" : "records not sorted by sha256");
    std::size_t breaking = 0;
    for (const auto& r : test) breaking += grammar::is_breaking(r.contract) ? 1 : 0;
    add("breaking", breaking == test.size(), std::to_string(breaking) + "/" + std::to_string(test.size()) + " test contracts scramble the translation block");
  }
  if (rule == "seen" || rule == "task_transfer" || rule == "unseen_composition") {
    std::string bad;
    for (const char* f : {"permutation", "sign", "scale", "target", "frame", "lag", "gripper_inverted"}) {
      const auto tr = detail::field_values(train, f);
      for (const auto& v : detail::field_values(test, f))
        if (!tr.count(v) && bad.empty()) bad = std::string(f) + " value " + v + " occurs in test but not in train";
    }
    add("field_support", bad.empty(), bad.empty() ? "every test field value occurs in train" : bad);
  }
  if (rule == "seen" || rule == "task_transfer") {
    std::set<std::vector<std::string>> sig;
    for (const auto& r : train) sig.insert(r.contract.composition_signature());
    std::string bad;
    for (const auto& r : test)
      if (!sig.count(r.contract.composition_signature()) && bad.empty())
        bad = "test signature [" + detail::join(r.contract.composition_signature()) + "] not in train";
    add("seen_compositions", bad.empty(), bad.empty() ? "every test composition occurs in train" : bad);
  }
  if (rule == "unseen_composition") {
    std::set<std::vector<std::string>> tr, te;
    for (const auto& r : train) tr.insert(r.contract.composition_signature());
    for (const auto& r : test) te.insert(r.contract.composition_signature());
    std::size_t overlap = 0;
    for (const auto& s : te) overlap += tr.count(s);
    add("composition_disjoint", overlap == 0, std::to_string(overlap) + " shared composition signatures");
  }
  if (rule == "unseen_value") {
    std::string bad;
    for (const auto& r : train)
      for (double s : r.contract.scale())
        for (double hv : splits::kHeldOutScales)
          if (s == hv && bad.empty()) bad = "train " + r.sha256.substr(0, 12) + " uses held-out scale " + python_float_repr(s);
    for (const auto& r : test)
      if (!splits::detail::has_held_out_scale(r.contract) && bad.empty())
        bad = "test " + r.sha256.substr(0, 12) + " uses no held-out scale";
    add("held_out_values", bad.empty(), bad.empty() ? "scales 0.5 and 2.0 only in test, in every test contract" : bad);
  }
  if (rule == "long_lag") {
    std::string bad;
    for (const auto& r : train)
      if (r.contract.lag() > 1 && bad.empty()) bad = "train " + r.sha256.substr(0, 12) + " has lag " + std::to_string(r.contract.lag());
    for (const auto& r : test)
      if (r.contract.lag() < 2 && bad.empty()) bad = "test " + r.sha256.substr(0, 12) + " has lag " + std::to_string(r.contract.lag());
    add("lag_split", bad.empty(), bad.empty() ? "train lags <= 1, test lags >= 2" : bad);
  }
  if (regenerate) {
    const auto rules = splits::all_rules();
    if (std::find(rules.begin(), rules.end(), rule) != rules.end()) {
      const Manifest again = splits::generate(rule, m.seed());
      const bool same = again.computed_sha256() == h && m.generator_version() == again.generator_version();
      add("regenerated", same, same ? "rule '" + rule + "' with seed " + std::to_string(m.seed()) + " reproduces the body"
                                    : "rule '" + rule + "' with seed " + std::to_string(m.seed()) + " gives " + again.computed_sha256());
    } else {
      add("regenerated", true, "skipped: custom rule '" + rule + "'");
    }
  }
  return out;
}

/// Checks across a set of manifests (by name): the full pool holds every generated split's test
/// contracts, reference9 holds the six reference contracts, and names are unique.
inline std::vector<Check> validate_set(const std::map<std::string, Manifest>& by_name) {
  std::vector<Check> out;
  auto pool_has = [&](const std::string& pool, const std::vector<std::string>& splits_) {
    auto it = by_name.find(pool);
    if (it == by_name.end()) return;
    std::set<std::string> members;
    for (const auto& r : it->second.members()) members.insert(r.contract.sha256());
    std::string bad;
    std::size_t n = 0;
    for (const auto& s : splits_) {
      auto sp = by_name.find(s);
      if (sp == by_name.end()) continue;
      for (const auto& r : sp->second.test()) {
        ++n;
        if (!members.count(r.contract.sha256()) && bad.empty()) bad = s + " contract " + r.sha256.substr(0, 12) + " missing";
      }
    }
    out.push_back({pool + "_covers_splits", bad.empty(),
                   bad.empty() ? "all " + std::to_string(n) + " contracts of " + detail::join(splits_, ", ") + " are members" : bad});
  };
  pool_has("full", splits::generated_split_rules());
  pool_has("reference9", splits::reference_split_rules());
  // the identifiers' training contracts share no hash with any contract of any other manifest
  if (auto it = by_name.find("identifier_training"); it != by_name.end()) {
    std::set<std::string> other;
    for (const auto& [name, m] : by_name)
      if (name != "identifier_training")
        for (const auto* list : {&m.train(), &m.test()})
          for (const auto& r : *list) other.insert(r.contract.sha256());
    std::string bad;
    std::size_t n = 0;
    for (const auto* list : {&it->second.train(), &it->second.test()})
      for (const auto& r : *list) {
        ++n;
        if (other.count(r.contract.sha256()) && bad.empty()) bad = "contract " + r.contract.sha256().substr(0, 12) + " is also in another manifest";
      }
    out.push_back({"identifier_training_disjoint", bad.empty(),
                   bad.empty() ? "none of its " + std::to_string(n) + " contracts is in any of the other " +
                                     std::to_string(by_name.size() - 1) + " manifests"
                               : bad});
  }
  return out;
}

}  // namespace actionshift
