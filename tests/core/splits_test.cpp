#include "actionshift/core/splits.hpp"
#include "actionshift/core/validate.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace actionshift {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

const Check* find(const std::vector<Check>& checks, const std::string& name) {
  for (const auto& c : checks)
    if (c.name == name) return &c;
  return nullptr;
}

void expect_all_ok(const std::vector<Check>& checks, const std::string& what) {
  for (const auto& c : checks) EXPECT_TRUE(c.ok) << what << ": " << c.name << ": " << c.detail;
}

TEST(Splits, EveryRuleIsReproducibleAndValid) {
  for (const auto& rule : splits::all_rules()) {
    const Manifest a = splits::generate(rule);
    const Manifest b = splits::generate(rule);
    EXPECT_EQ(a.serialize(), b.serialize()) << rule;
    expect_all_ok(validate(a), rule);
  }
}

TEST(Splits, GeneratedSplitsHaveAtLeast32BreakingTestContracts) {
  for (const auto& rule : splits::generated_split_rules()) {
    const Manifest m = splits::generate(rule);
    EXPECT_GE(m.test().size(), 32u) << rule;
    for (const auto& r : m.test()) {
      EXPECT_TRUE(grammar::is_breaking(r.contract)) << rule;
      EXPECT_TRUE(grammar::violations(r.contract).empty()) << rule;
    }
  }
}

TEST(Splits, RuleSpecificProperties) {
  const Manifest lag = splits::generate("long_lag");
  for (const auto& r : lag.train()) EXPECT_LE(r.contract.lag(), 1);
  for (const auto& r : lag.test()) EXPECT_GE(r.contract.lag(), 2);
  const Manifest uc = splits::generate("unseen_composition");
  for (const auto& r : uc.train()) EXPECT_LE(r.contract.composition_signature().size(), 1u);
  for (const auto& r : uc.test()) {
    EXPECT_GE(r.contract.composition_signature().size(), 3u);
    EXPECT_EQ(r.contract.lag(), 0);
  }
  EXPECT_EQ(find(validate(uc), "composition_disjoint")->detail, "0 shared composition signatures");
  const Manifest seen = splits::generate("seen");
  for (const auto& r : seen.test()) {
    EXPECT_EQ(r.contract.lag(), 0);
    EXPECT_EQ(r.contract.target(), Target::kDelta);
  }
  // different seeds give different contracts
  EXPECT_NE(splits::generate("seen", 1).computed_sha256(), seen.computed_sha256());
}

TEST(Splits, ReferenceManifestsAndPools) {
  const Manifest p9 = splits::generate("reference9");
  EXPECT_TRUE(p9.is_pool());
  EXPECT_EQ(p9.members().size(), 9u);
  EXPECT_EQ(p9.pool_sha256(), "b177b082925800655dee9e93c02142f26a703fd2bdf1d97be56a2cb0bf0eeea3");
  const Manifest rs = splits::generate("reference_seen");
  ASSERT_EQ(rs.test().size(), 2u);
  EXPECT_EQ(rs.test()[0].sha256, "d1bb0bda71fc3b1aff5372b4c4d64823538015fe4d9be25252621523ccff41a6");
  const Manifest full = splits::generate("full");
  EXPECT_EQ(full.members().size(), static_cast<std::size_t>(splits::kFullPoolSize));
  EXPECT_EQ(full.members()[0].contract, Contract::identity());
  EXPECT_GE(full.metadata()["distractors"].get<int>(), 16);
  std::map<std::string, Manifest> set;
  for (const auto& rule : splits::all_rules()) set.emplace(rule, splits::generate(rule));
  expect_all_ok(validate_set(set), "set");
}

TEST(Splits, TamperingIsDetected) {
  const Manifest m = splits::generate("unseen_composition");
  std::string text = m.serialize();
  // change one number of one contract's scale, keep the stored hashes
  const auto pos = text.find("\"scale\":[") + 9;
  text[pos] = text[pos] == '1' ? '2' : '1';
  const Manifest t = Manifest::parse(text, "tampered.json");
  const auto checks = validate(t);
  EXPECT_FALSE(find(checks, "record_hashes")->ok);
  EXPECT_FALSE(find(checks, "manifest_hash")->ok);
  EXPECT_FALSE(find(checks, "regenerated")->ok);
  // moving a test contract into train breaks disjointness of compositions
  auto train = m.train_contracts();
  train.push_back(m.contracts().front());
  const Manifest leak = Manifest::split("unseen_composition", "unseen_composition", m.seed(), m.description(), m.metadata(), train, m.contracts());
  EXPECT_FALSE(find(validate(leak), "disjoint_contracts")->ok);
  EXPECT_FALSE(find(validate(leak), "composition_disjoint")->ok);
}

TEST(Splits, ParseRoundTripAndErrors) {
  const Manifest m = splits::generate("seen");
  EXPECT_EQ(Manifest::parse(m.serialize(), "x").serialize(), m.serialize());
  EXPECT_THAT([] { Manifest::parse("", "a.json"); }, ThrowsMessage<InputError>(HasSubstr("a.json: not valid JSON")));
  EXPECT_THAT([] { Manifest::parse("[]", "a.json"); }, ThrowsMessage<InputError>(HasSubstr("must be a JSON object")));
  nlohmann::json j = nlohmann::json::parse(m.serialize());
  j["test"][3]["contract"]["scale"][0] = -1.0;
  EXPECT_THAT([&] { Manifest::parse(j.dump(), "b.json"); },
              ThrowsMessage<InputError>(HasSubstr("b.json: test[3].contract: scale values must be finite and positive")));
  j = nlohmann::json::parse(m.serialize());
  j["bogus"] = 1;
  EXPECT_THAT([&] { Manifest::parse(j.dump(), "c.json"); }, ThrowsMessage<InputError>(HasSubstr("c.json: bogus: unknown field")));
  j = nlohmann::json::parse(m.serialize());
  j.erase("seed");
  EXPECT_THAT([&] { Manifest::parse(j.dump(), "d.json"); }, ThrowsMessage<InputError>(HasSubstr("d.json: seed: missing field")));
  EXPECT_THAT([] { splits::generate("nope"); }, ThrowsMessage<std::invalid_argument>(HasSubstr("unknown split rule: nope")));
}

TEST(Splits, CommittedManifestsEqualTheGeneratorOutputAndPassEveryCheck) {
  const std::filesystem::path dir = std::filesystem::path(ACTIONSHIFT_SOURCE_DIR) / "manifests";
  for (const auto& rule : splits::all_rules()) {
    const auto path = dir / (rule + ".json");
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    EXPECT_EQ(ss.str(), splits::generate(rule).serialize()) << path << " differs from the generator";
    const Manifest m = Manifest::load(path.string());
    expect_all_ok(validate(m), path.string());
    // the grammar grids cover every contract in every manifest (docs/semantics.md)
    for (const auto* list : {&m.train(), &m.test()})
      for (const auto& r : *list) EXPECT_TRUE(grammar::violations(r.contract).empty()) << path;
  }
}

// The learned identifiers' training contracts (manifests/identifier_training.json) must never be
// evaluation contracts: no hash in it may occur in any other committed manifest (train, test or
// pool member), and the validator's cross-manifest check must catch a leaked one.
TEST(Splits, IdentifierTrainingContractsShareNoHashWithAnyEvaluationManifest) {
  const std::filesystem::path dir = std::filesystem::path(ACTIONSHIFT_SOURCE_DIR) / "manifests";
  std::map<std::string, Manifest> by_name;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".json") by_name.emplace(e.path().stem().string(), Manifest::load(e.path().string()));
  ASSERT_TRUE(by_name.count("identifier_training"));
  ASSERT_GE(by_name.size(), 11u);
  const Manifest& id = by_name.at("identifier_training");
  EXPECT_EQ(id.train().size(), static_cast<std::size_t>(splits::kIdentifierTrainSize));
  EXPECT_EQ(id.test().size(), static_cast<std::size_t>(splits::kIdentifierHeldOutSize));
  std::set<std::string> evaluation;
  for (const auto& [name, m] : by_name)
    if (name != "identifier_training")
      for (const auto* list : {&m.train(), &m.test()})
        for (const auto& r : *list) evaluation.insert(r.contract.sha256());
  ASSERT_GT(evaluation.size(), 300u);
  for (const auto* list : {&id.train(), &id.test()})
    for (const auto& r : *list) EXPECT_EQ(evaluation.count(r.contract.sha256()), 0u) << "training contract " << r.sha256 << " is evaluated";
  // the whole grammar is drawn: every target, frame and lag occurs
  std::set<std::string> fields;
  for (const auto& r : id.train())
    fields.insert(std::string(to_string(r.contract.target())) + "/" + to_string(r.contract.frame()) + "/" + std::to_string(r.contract.lag()));
  EXPECT_GE(fields.size(), 12u);
  expect_all_ok(validate_set(by_name), "committed set");
  // a leaked evaluation contract is caught by the validator
  auto train = id.train_contracts();
  train.push_back(by_name.at("reference_seen").contracts().front());
  by_name.insert_or_assign("identifier_training", Manifest::split("identifier_training", "identifier_training", id.seed(),
                                                                  id.description(), id.metadata(), train, id.contracts()));
  const auto checks = validate_set(by_name);
  EXPECT_FALSE(find(checks, "identifier_training_disjoint")->ok);
}

}  // namespace
}  // namespace actionshift
