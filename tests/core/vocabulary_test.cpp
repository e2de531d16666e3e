// The core vocabularies: every name prints and parses back, an unknown name is a one-line InputError
// naming the source, the field and the valid names.
#include "actionshift/core/vocabulary.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

using namespace actionshift;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {

template <class V>
void round_trips(const V& vocabulary) {
  for (const auto& e : vocabulary.entries) {
    EXPECT_EQ(vocabulary.name(e.value), e.name);
    EXPECT_EQ(vocabulary.parse(e.name, "src", "field"), e.value);
  }
}

}  // namespace

TEST(Vocabulary, EveryNamePrintsAndParsesBack) {
  round_trips(kRotationModes);
  round_trips(kProfiles);
  round_trips(kVerdicts);
  EXPECT_EQ(rotation_mode_name(RotationMode::kIdentity), "identity");
  EXPECT_EQ(parse_profile("ideal"), Profile::kIdeal);
  EXPECT_EQ(verdict_name(Verdict::kExtendSeeds), "extend_seeds");
}

TEST(Vocabulary, UnknownNamesAreOneLineErrorsNamingSourceFieldAndValidNames) {
  EXPECT_THAT([] { (void)parse_rotation_mode("tool", "x.yaml:7", "rotation_mode"); },
              ThrowsMessage<InputError>("x.yaml:7: rotation_mode: unknown rotation mode 'tool' (valid: live, identity)"));
  EXPECT_THAT([] { (void)parse_profile("physx", "job.json", "profile"); },
              ThrowsMessage<InputError>("job.json: profile: unknown fidelity profile 'physx' (valid: maniskill, ideal)"));
  EXPECT_THAT([] { (void)parse_verdict("passed", "v.json", "cells.a.verdict"); },
              ThrowsMessage<InputError>(HasSubstr("v.json: cells.a.verdict: unknown verdict 'passed' (valid: pass, fail,")));
}

TEST(Vocabulary, PositiveVerdictsAreTheOnesWhoseLossRegresses) {
  for (const auto& e : kVerdicts.entries)
    EXPECT_EQ(is_positive(e.value), e.name == "pass" || e.name == "advance" || e.name == "promote") << e.name;
}
