// decide_verdict as a pure function (docs/reference.md, *Self-test*): the six guarantees, the diff sentences and
// the renderings.
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/selftest/library.hpp"
#include "actionshift/selftest/verdict.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace actionshift::selftest {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

Evidence confident(const Contract& expected, const Contract& identified) {
  Evidence e;
  e.expected = expected;
  e.identified = identified;
  e.confidence.fill(0.99);
  e.fit_ratio = 1.0;
  e.map_posterior = 0.99;
  return e;
}

const Contract kMiswired = *named_contract("miswired");

// 1. every checked field resolved and equal: PASS
TEST(Verdict, PassesOnlyWhenEveryCheckedFieldIsResolvedAndEqual) {
  const Verdict v = decide_verdict(confident(Contract::identity(), Contract::identity()), 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kPass);
  EXPECT_EQ(v.exit_code(), 0);
  EXPECT_EQ(v.reason, "every observable field resolved with high confidence and matches the expected wiring");
  EXPECT_TRUE(v.unresolved_fields.empty());
}

// 2. a confidently resolved field that differs: MISMATCH with the diff in words
TEST(Verdict, ConfidentDiffIsAMismatchInWords) {
  const Verdict v = decide_verdict(confident(Contract::identity(), kMiswired), 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kMismatch);
  EXPECT_EQ(v.exit_code(), 1);
  EXPECT_EQ(v.reason, "channels 0 and 1 SWAPPED; channel 3 sign FLIPPED");
  EXPECT_THAT(v.diff_fields, ElementsAre("permutation", "sign"));
}

// 3. a diff below the floor is not asserted: with nothing confident to report, abstain
TEST(Verdict, UnconfidentDiffAbstainsRatherThanGuessing) {
  Evidence e = confident(Contract::identity(), kMiswired);
  e.confidence[static_cast<std::size_t>(Field::kPermutation)] = 0.6;
  e.confidence[static_cast<std::size_t>(Field::kSign)] = 0.89;
  const Verdict v = decide_verdict(e, 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kInconclusive);
  EXPECT_EQ(v.exit_code(), 2);
  EXPECT_EQ(v.reason,
            "insufficient posterior mass to resolve field(s) ['permutation', 'sign'] (weakest 0.60 < floor 0.90). "
            "Abstaining rather than guessing.");
  EXPECT_TRUE(v.field_diffs.empty());
}

// printed numbers never contradict the comparison they report
TEST(Verdict, PrintedComparisonsNeverContradictThemselves) {
  Evidence e = confident(Contract::identity(), Contract::identity());
  e.confidence[static_cast<std::size_t>(Field::kPermutation)] = 0.8996;
  Verdict v = decide_verdict(e, 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kInconclusive);
  EXPECT_THAT(v.reason, HasSubstr("(weakest 0.8996 < floor 0.9000)"));
  e = confident(Contract::identity(), Contract::identity());
  e.fit_ratio = 4.04;
  v = decide_verdict(e, 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kInconclusive);
  EXPECT_THAT(v.reason, HasSubstr("at 4.04x the calibrated noise scale (threshold 4.00x)"));
  EXPECT_THAT(to_text(v, {}), HasSubstr("fit residual: 4.04x calibrated noise scale (TOO LARGE, > 4.00x)"));
  e.fit_ratio = 4.0;  // equal is not above the threshold
  EXPECT_THAT(to_text(decide_verdict(e, 0.9, 4.0), {}), HasSubstr("fit residual: 4.00x calibrated noise scale (ok, <= 4.00x)"));
}

// 4. a mismatch still names the unresolved fields as outside the verdict
TEST(Verdict, MismatchNotesUnresolvedFields) {
  Evidence e = confident(Contract::identity(), kMiswired);
  e.confidence[static_cast<std::size_t>(Field::kSign)] = 0.5;
  e.confidence[static_cast<std::size_t>(Field::kLag)] = 0.5;
  const Verdict v = decide_verdict(e, 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kMismatch);
  EXPECT_EQ(v.reason,
            "channels 0 and 1 SWAPPED (note: field(s) ['sign', 'lag'] were not resolved and are not part of this verdict)");
}

// 5. misspecification beats everything: a confident diff with a bad fit is an abstention
TEST(Verdict, MisspecificationAbstainsEvenWithConfidentFields) {
  Evidence e = confident(Contract::identity(), kMiswired);
  e.fit_ratio = 41.22;
  const Verdict v = decide_verdict(e, 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kInconclusive);
  EXPECT_EQ(v.reason,
            "response misspecification: the best hypothesis fits the probe responses at 41.2x the calibrated noise scale "
            "(threshold 4.0x) -- the true wiring is likely outside the declared pool. Abstaining.");
  EXPECT_TRUE(v.field_diffs.empty());
  EXPECT_EQ(v.unresolved_fields.size(), 6u);
  e.fit_ratio = 4.0;  // at the threshold: still trusted
  EXPECT_EQ(decide_verdict(e, 0.9, 4.0).status, Status::kMismatch);
}

// 6. fields that cannot be checked never decide the verdict, and gripper polarity is always listed
TEST(Verdict, UncheckedFieldsNeverEnterTheVerdict) {
  Evidence e = confident(Contract::identity(), reference::with(Contract::identity(), "delta", "tool", 0));
  e.checkable[static_cast<std::size_t>(Field::kFrame)] = false;
  e.unchecked_reason[static_cast<std::size_t>(Field::kFrame)] = "tool frame under identity rotation";
  e.confidence[static_cast<std::size_t>(Field::kFrame)] = 0.1;
  const Verdict v = decide_verdict(e, 0.9, 4.0);
  EXPECT_EQ(v.status, Status::kPass);
  ASSERT_EQ(v.unchecked.size(), 2u);
  EXPECT_EQ(v.unchecked[0].field, "gripper_inverted");
  EXPECT_EQ(v.unchecked[1].field, "frame");
  // a gripper-only difference is invisible to a pose probe: never a mismatch
  ContractFields f;
  f.gripper_inverted = true;
  EXPECT_EQ(decide_verdict(confident(Contract::identity(), Contract::make(f)), 0.9, 4.0).status, Status::kPass);
}

TEST(Verdict, FloorIsInclusive) {
  Evidence e = confident(Contract::identity(), Contract::identity());
  e.confidence.fill(0.9);
  EXPECT_EQ(decide_verdict(e, 0.9, 4.0).status, Status::kPass);
  e.confidence[0] = 0.8999;
  EXPECT_EQ(decide_verdict(e, 0.9, 4.0).status, Status::kInconclusive);
}

// ---- diff sentences

TEST(DiffSentence, FollowsTheReferenceWording) {
  const Contract id;
  ContractFields f;
  f.permutation = {1, 2, 0, 3, 4, 5};
  f.sign = {-1, 1, 1, 1, 1, -1};
  f.scale = {1.0, 1.25, 1.0, 1.0, 1.0, 0.6};
  f.target = "absolute";
  f.frame = "tool";
  f.lag = 4;
  const Contract c = Contract::make(f);
  EXPECT_EQ(diff_sentence(id, c, Field::kPermutation),
            "channel routing changed at channels [0, 1, 2]: expected permutation (0, 1, 2, 3, 4, 5), wired (1, 2, 0, 3, 4, 5)");
  EXPECT_EQ(diff_sentence(id, c, Field::kSign), "channels [0, 5] sign FLIPPED");
  EXPECT_EQ(diff_sentence(id, c, Field::kScale), "channel 1 scale 1->1.25; channel 5 scale 1->0.6");
  EXPECT_EQ(diff_sentence(id, c, Field::kTarget), "target encoding differs: expected delta, wired absolute");
  EXPECT_EQ(diff_sentence(id, c, Field::kFrame), "reference frame differs: expected base, wired tool");
  EXPECT_EQ(diff_sentence(id, c, Field::kLag), "actuation lag differs: expected 0 step(s), wired 4 step(s)");
  for (Field fl : all_fields()) EXPECT_EQ(diff_sentence(c, c, fl), "");
  // in a bijection, exactly two differing outputs are always an exchange of their inputs
  ContractFields g;
  g.permutation = {2, 0, 1, 3, 4, 5};
  const Contract b = Contract::make(g);
  g.permutation = {0, 2, 1, 3, 4, 5};
  EXPECT_EQ(diff_sentence(b, Contract::make(g), Field::kPermutation), "channels 0 and 1 SWAPPED");
}

TEST(FieldValue, PrintsPythonStyle) {
  const Contract oc = reference::oracle_contract();
  EXPECT_EQ(field_value(oc, Field::kPermutation), "(1, 0, 2, 4, 5, 3)");
  EXPECT_EQ(field_value(oc, Field::kSign), "(-1, 1, -1, 1, -1, 1)");
  EXPECT_EQ(field_value(oc, Field::kScale), "(0.5, 2.0, 1.5, 0.75, 1.25, 0.6)");
  EXPECT_EQ(field_value(oc, Field::kTarget), "delta");
  EXPECT_EQ(field_value(oc, Field::kLag), "0");
}

// ---- renderings

TEST(Report, TextHasTheReferenceLayout) {
  Verdict v = decide_verdict(confident(Contract::identity(), kMiswired), 0.9, 4.0);
  v.probe_steps = 6;
  v.displacement = 0.0123;
  ReportHeader h;
  h.task = "pick_cube";
  h.backend = "synthetic";
  h.budget = 6;
  h.pool_size = 8;
  const std::string t = to_text(v, h);
  EXPECT_THAT(t, HasSubstr("ActionShift plug-and-verify self-test\n=====================================\n"
                           "Task:           pick_cube (synthetic)\n"
                           "Probe strategy: entropy   budget 6 steps   amplitude 0.5\n"
                           "Declared pool:  8 candidate wirings\n"));
  EXPECT_THAT(t, HasSubstr("  permutation  (1, 0, 2, 3, 4, 5)               confidence 0.99\n"));
  EXPECT_THAT(t, HasSubstr("  gripper_inverted not checked (out of scope for a pose probe)\n"));
  EXPECT_THAT(t, HasSubstr("  fit residual: 1.00x calibrated noise scale (ok, <= 4.00x)\n"));
  EXPECT_THAT(t, HasSubstr("displacement during probing: 0.0123 m path over 6 probe steps"));
  EXPECT_THAT(t, HasSubstr("\nVERDICT: MISMATCH  (exit 1)\n  channels 0 and 1 SWAPPED; channel 3 sign FLIPPED\n"));
}

TEST(Report, JsonCarriesTheReferenceKeys) {
  const Verdict v = decide_verdict(confident(Contract::identity(), kMiswired), 0.9, 4.0);
  const auto j = nlohmann::json::parse(to_json(v, {}));
  for (const char* k : {"status", "exit_code", "reason", "strategy", "identified_contract", "expected_contract",
                        "field_confidence", "unchecked_fields", "unresolved_fields", "field_diffs", "fit_ratio",
                        "probe_steps", "probe_displacement", "map_posterior"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["status"], "MISMATCH");
  EXPECT_EQ(j["exit_code"], 1);
  EXPECT_EQ(Contract::from_json_value(j["identified_contract"]), kMiswired);
  EXPECT_EQ(j["unchecked_fields"], nlohmann::json::array({"gripper_inverted"}));
  EXPECT_EQ(j["field_diffs"], nlohmann::json::array({"channels 0 and 1 SWAPPED", "channel 3 sign FLIPPED"}));
}

}  // namespace
}  // namespace actionshift::selftest
