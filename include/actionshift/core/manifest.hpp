#pragma once
/// \file Split manifests and contract pools (rules in docs/splits.md).
///
/// A manifest is a JSON file holding its schema version, generator version, rule, seed, a short
/// description, optional metadata, the contracts in canonical form (each with its hash and
/// composition signature) and `manifest_sha256`: the sha256 of the canonical JSON of everything
/// else. A *split* has `train` and `test` lists (evaluation runs on `test`, in file order:
/// contract index i is test[i]); a *pool* has an ordered `members` list and also records
/// `pool_sha256` (sha256 of the member hashes concatenated in order, as the reference).

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/core/rng.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift {

inline constexpr const char* kManifestSchema = "actionshift-manifest/1";
inline constexpr const char* kGeneratorVersion = "grammar-v1";
inline constexpr std::uint64_t kDefaultSeed = 20260718;  ///< the reference's first experimental seed

/// One contract entry as stored: the contract plus the hash and signature written beside it.
struct ManifestRecord {
  Contract contract;
  std::string sha256;                    ///< as stored in the file (validate() recomputes it)
  std::vector<std::string> composition;  ///< as stored in the file

  static ManifestRecord of(const Contract& c) { return {c, c.sha256(), c.composition_signature()}; }
  nlohmann::json to_json_value() const {
    return {{"composition", composition}, {"contract", contract.to_json_value()}, {"sha256", sha256}};
  }
};

/// An immutable split manifest or pool. Build with Manifest::split()/pool() or parse().
class Manifest {
 public:
  enum class Kind { kSplit, kPool };

  static Manifest split(std::string name, std::string rule, std::uint64_t seed, std::string description,
                        nlohmann::json metadata, const std::vector<Contract>& train,
                        const std::vector<Contract>& test) {
    Manifest m(Kind::kSplit, std::move(name), std::move(rule), seed, std::move(description), std::move(metadata));
    for (const auto& c : train) m.train_.push_back(ManifestRecord::of(c));
    for (const auto& c : test) m.test_.push_back(ManifestRecord::of(c));
    m.seal();
    return m;
  }
  static Manifest pool(std::string name, std::string rule, std::uint64_t seed, std::string description,
                       nlohmann::json metadata, const std::vector<Contract>& members) {
    Manifest m(Kind::kPool, std::move(name), std::move(rule), seed, std::move(description), std::move(metadata));
    for (const auto& c : members) m.test_.push_back(ManifestRecord::of(c));
    m.seal();
    return m;
  }

  /// Parses a manifest file's text. Throws InputError(source, field, reason) for malformed
  /// structure or an invalid contract. Hashes are NOT checked here: see validate().
  static Manifest parse(std::string_view text, const std::string& source) {
    const nlohmann::json j = parse_json_input(text, source);
    if (!j.is_object()) throw InputError(source, "", "manifest must be a JSON object");
    auto str = [&](const char* k) -> std::string {
      if (!j.contains(k)) throw InputError(source, k, "missing field");
      if (!j[k].is_string()) throw InputError(source, k, "must be a string");
      return j[k].get<std::string>();
    };
    static const std::set<std::string> kAllowed{"schema_version", "generator_version", "kind", "name", "rule", "seed",
                                                "description", "metadata", "train", "test", "members",
                                                "pool_sha256", "manifest_sha256"};
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!kAllowed.count(it.key())) throw InputError(source, it.key(), "unknown field");
    const std::string schema = str("schema_version");
    if (schema != kManifestSchema)
      throw InputError(source, "schema_version", "unsupported " + quote_input(schema) + " (expected " + quote_input(kManifestSchema) + ")");
    const std::string kind = str("kind");
    if (kind != "split" && kind != "pool") throw InputError(source, "kind", "must be 'split' or 'pool' (got " + quote_input(kind) + ")");
    if (!j.contains("seed")) throw InputError(source, "seed", "missing field");
    if (!j["seed"].is_number_unsigned()) throw InputError(source, "seed", "must be a nonnegative integer");
    Manifest m(kind == "split" ? Kind::kSplit : Kind::kPool, str("name"), str("rule"), j["seed"].get<std::uint64_t>(),
               str("description"), j.contains("metadata") ? j["metadata"] : nlohmann::json::object());
    m.generator_version_ = str("generator_version");
    if (!m.metadata_.is_object()) throw InputError(source, "metadata", "must be an object");
    auto records = [&](const char* key, std::vector<ManifestRecord>& out) {
      if (!j.contains(key)) throw InputError(source, key, "missing field");
      if (!j[key].is_array()) throw InputError(source, key, "must be a list");
      std::size_t i = 0;
      for (const auto& r : j[key]) {
        const std::string where = std::string(key) + "[" + std::to_string(i++) + "]";
        if (!r.is_object() || !r.contains("contract") || !r.contains("sha256") || !r.contains("composition") || r.size() != 3)
          throw InputError(source, where, "record must have exactly the fields composition, contract, sha256");
        if (!r["sha256"].is_string()) throw InputError(source, where + ".sha256", "must be a string");
        if (!r["composition"].is_array()) throw InputError(source, where + ".composition", "must be a list");
        ManifestRecord rec;
        try {
          rec.contract = Contract::from_json_value(r["contract"]);
        } catch (const std::invalid_argument& e) {
          throw InputError(source, where + ".contract", e.what());
        }
        rec.sha256 = r["sha256"].get<std::string>();
        for (const auto& s : r["composition"]) {
          if (!s.is_string()) throw InputError(source, where + ".composition", "must be a list of strings");
          rec.composition.push_back(s.get<std::string>());
        }
        out.push_back(std::move(rec));
      }
    };
    if (m.kind_ == Kind::kSplit) {
      if (j.contains("members") || j.contains("pool_sha256"))
        throw InputError(source, "members", "a split has train and test lists, not members");
      records("train", m.train_);
      records("test", m.test_);
    } else {
      if (j.contains("train") || j.contains("test"))
        throw InputError(source, "train", "a pool has a members list, not train/test");
      records("members", m.test_);
      m.stored_pool_sha256_ = str("pool_sha256");
    }
    m.stored_sha256_ = str("manifest_sha256");
    return m;
  }

  /// Reads and parses a manifest file. Throws InputError naming the file.
  static Manifest load(const std::string& path) {
    const std::string text = read_input_file(path, "a manifest file", kMaxManifestBytes);
    if (text.empty()) throw InputError(path, "", "file is empty");
    return parse(text, path);
  }

  Kind kind() const noexcept { return kind_; }
  bool is_pool() const noexcept { return kind_ == Kind::kPool; }
  const std::string& name() const noexcept { return name_; }
  const std::string& rule() const noexcept { return rule_; }
  const std::string& generator_version() const noexcept { return generator_version_; }
  std::uint64_t seed() const noexcept { return seed_; }
  const std::string& description() const noexcept { return description_; }
  const nlohmann::json& metadata() const noexcept { return metadata_; }
  const std::vector<ManifestRecord>& train() const noexcept { return train_; }
  /// Evaluation contracts of a split, or the members of a pool, in order.
  const std::vector<ManifestRecord>& test() const noexcept { return test_; }
  const std::vector<ManifestRecord>& members() const noexcept { return test_; }

  /// The evaluation contracts (split) or members (pool), in order: contract index i is [i].
  std::vector<Contract> contracts() const {
    std::vector<Contract> out;
    for (const auto& r : test_) out.push_back(r.contract);
    return out;
  }
  std::vector<Contract> train_contracts() const {
    std::vector<Contract> out;
    for (const auto& r : train_) out.push_back(r.contract);
    return out;
  }

  /// The hash written in the file (for a parsed manifest) or computed (for a built one).
  const std::string& manifest_sha256() const noexcept { return stored_sha256_; }
  /// sha256 of the canonical body as it is now.
  std::string computed_sha256() const { return sha256_hex(canonical_dump(body())); }
  /// Pool hash written in the file (pools only; empty for splits).
  const std::string& stored_pool_sha256() const noexcept { return stored_pool_sha256_; }
  /// Pool hash of contracts(), recomputed.
  std::string pool_sha256() const { return actionshift::pool_sha256(contracts()); }

  /// The hashed body: every field except manifest_sha256.
  nlohmann::json body() const {
    nlohmann::json j;
    j["schema_version"] = kManifestSchema;
    j["generator_version"] = generator_version_;
    j["kind"] = kind_ == Kind::kSplit ? "split" : "pool";
    j["name"] = name_;
    j["rule"] = rule_;
    j["seed"] = seed_;
    j["description"] = description_;
    j["metadata"] = metadata_;
    auto list = [](const std::vector<ManifestRecord>& v) {
      nlohmann::json a = nlohmann::json::array();
      for (const auto& r : v) a.push_back(r.to_json_value());
      return a;
    };
    if (kind_ == Kind::kSplit) {
      j["train"] = list(train_);
      j["test"] = list(test_);
    } else {
      j["members"] = list(test_);
      j["pool_sha256"] = stored_pool_sha256_;
    }
    return j;
  }

  /// The file text: sorted keys, two-space indent, one canonical record per line, newline-terminated.
  std::string serialize() const {
    nlohmann::json j = body();
    j["manifest_sha256"] = stored_sha256_;
    std::string out = "{\n";
    bool first = true;
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (!first) out += ",\n";
      first = false;
      out += "  " + canonical_dump(it.key()) + ": ";
      if (it.value().is_array()) {
        if (it.value().empty()) {
          out += "[]";
          continue;
        }
        out += "[\n";
        for (std::size_t i = 0; i < it.value().size(); ++i)
          out += "    " + canonical_dump(it.value()[i]) + (i + 1 < it.value().size() ? ",\n" : "\n");
        out += "  ]";
      } else {
        out += canonical_dump(it.value());
      }
    }
    return out + "\n}\n";
  }

  bool operator==(const Manifest& o) const { return serialize() == o.serialize(); }

 private:
  Manifest(Kind kind, std::string name, std::string rule, std::uint64_t seed, std::string description,
           nlohmann::json metadata)
      : kind_(kind),
        name_(std::move(name)),
        rule_(std::move(rule)),
        generator_version_(kGeneratorVersion),
        seed_(seed),
        description_(std::move(description)),
        metadata_(metadata.is_null() ? nlohmann::json::object() : std::move(metadata)) {}

  void seal() {
    if (kind_ == Kind::kPool) stored_pool_sha256_ = pool_sha256();
    stored_sha256_ = computed_sha256();
  }

  Kind kind_;
  std::string name_, rule_, generator_version_;
  std::uint64_t seed_{kDefaultSeed};
  std::string description_;
  nlohmann::json metadata_;
  std::vector<ManifestRecord> train_, test_;
  std::string stored_sha256_, stored_pool_sha256_;
};

}  // namespace actionshift
