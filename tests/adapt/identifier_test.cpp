// The learned identifiers (osi, probe_osi, recurrent_osi): privilege, weight format, heads, acting
#include "actionshift/adapt/identifier.hpp"

#include "actionshift/adapt/registry.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/transforms.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace actionshift::adapt {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// ---- privilege: the network only (the public reference implementation's invariant: constructors take no contract)
using WeightsPtr = std::shared_ptr<const IdentifierWeights>;
static_assert(std::is_constructible_v<IdentifierAdapter, WeightsPtr, IdentifierOptions>);
static_assert(!std::is_constructible_v<IdentifierAdapter, Contract>);
static_assert(!std::is_constructible_v<IdentifierAdapter, WeightsPtr, Contract>);
static_assert(!std::is_constructible_v<IdentifierAdapter, WeightsPtr, IdentifierOptions, Contract>);
static_assert(!std::is_constructible_v<IdentifierAdapter, WeightsPtr, std::vector<Contract>>);
static_assert(!std::is_constructible_v<IdentifierAdapter, WeightsPtr, IdentifierOptions, std::vector<Contract>>);
static_assert(!std::is_constructible_v<IdentifierAdapter, WeightsPtr, ResponseModel>);
static_assert(!std::is_constructible_v<IdentifierAdapter, std::vector<Contract>, ResponseModel>);
static_assert(!std::is_constructible_v<IdentifierState, Contract>);

Contract sample_contract() {
  ContractFields f;
  f.permutation = {2, 0, 1, 3, 5, 4};
  f.sign = {1, -1, 1, -1, 1, 1};
  f.scale = {0.5, 2.0, 1.0, 1.25, 0.6, 0.75};
  f.target = "absolute";
  f.frame = "tool";
  f.lag = 0;
  f.gripper_inverted = true;
  return Contract::make(f);
}

// logits that put all the mass on `c`
Eigen::VectorXf logits_of(const Contract& c) {
  Eigen::VectorXf z = Eigen::VectorXf::Zero(heads::kOutputs);
  const auto l = FieldLabels::of(c);
  for (int i = 0; i < kPoseDim; ++i) {
    const auto k = static_cast<std::size_t>(i);
    z[heads::kPermutation + 6 * i + l.permutation[k]] = 10;
    z[heads::kSign + 2 * i + l.sign[k]] = 10;
    z[heads::kScale + 7 * i + l.scale[k]] = 10;
  }
  z[heads::kTarget + l.target] = 10;
  z[heads::kFrame + l.frame] = 10;
  z[heads::kLag + l.lag] = 10;
  z[heads::kGripper + l.gripper] = 10;
  return z;
}

// a network whose output ignores its input and names `c` (last layer zero, bias = c's logits)
IdentifierWeights constant_net(IdentifierKind kind, const Contract& c) {
  const bool rec = kind == IdentifierKind::kRecurrentOsi;
  IdentifierWeights w = IdentifierWeights::init(kind, "pick_cube", rec ? 0 : 14, rec ? 90 : 0, rec ? std::vector<int>{64} : std::vector<int>{64, 64}, 7);
  w.w.back().setZero();
  w.b.back() = logits_of(c);
  return w;
}

TEST(Identifier, LogitsDecodeToTheirContractAndLabelsRoundTrip) {
  for (const Contract& c : {sample_contract(), Contract::identity()}) EXPECT_EQ(decode_logits(logits_of(c)), c);
  const auto a = field_agreement(sample_contract(), Contract::identity());
  // permutation: rows 3 agree (1/6); sign: 4 of 6; scale: 1 of 6 (channel 2); target, frame, lag 0 vs 0, gripper
  EXPECT_NEAR(a[0], 1.0 / 6, 1e-12);
  EXPECT_NEAR(a[1], 4.0 / 6, 1e-12);
  EXPECT_NEAR(a[2], 1.0 / 6, 1e-12);
  EXPECT_EQ(a[3], 0.0);
  EXPECT_EQ(a[4], 0.0);
  EXPECT_EQ(a[5], 1.0);
  EXPECT_EQ(a[6], 0.0);
}

TEST(Identifier, PermutationHeadsAlwaysDecodeToABijection) {
  // every row prefers raw channel 0: the greedy assignment gives the most confident row channel 0
  // and every other row its best free channel
  Eigen::VectorXf z = Eigen::VectorXf::Zero(heads::kOutputs);
  for (int i = 0; i < kPoseDim; ++i) {
    z[heads::kPermutation + 6 * i + 0] = 5.0f + static_cast<float>(i);  // row 5 is the most confident
    z[heads::kPermutation + 6 * i + (i % 5) + 1] = 4.0f;
  }
  const Contract c = decode_logits(z);
  std::array<int, 6> p = c.permutation();
  EXPECT_EQ(p[5], 0);
  std::sort(p.begin(), p.end());
  EXPECT_EQ(p, (std::array<int, 6>{0, 1, 2, 3, 4, 5}));
  EXPECT_THROW(decode_logits(Eigen::VectorXf::Zero(7)), std::invalid_argument);
}

TEST(Identifier, WeightFileRoundTripsAndRejectsCorruption) {
  for (auto kind : {IdentifierKind::kOsi, IdentifierKind::kRecurrentOsi}) {
    IdentifierWeights w = constant_net(kind, sample_contract());
    w.training = {{"seed", 5}};
    const std::string bytes = serialize_identifier(w);
    const IdentifierWeights r = parse_identifier(bytes, "w.asid");
    EXPECT_EQ(serialize_identifier(r), bytes);
    EXPECT_EQ(r.parameter_count(), w.parameter_count());
    EXPECT_EQ(r.training["seed"], 5);
    std::string bad = bytes;
    bad[bad.size() - 3] ^= 0x40;
    EXPECT_THAT([&] { parse_identifier(bad, "w.asid"); }, ThrowsMessage<InputError>(HasSubstr("w.asid: payload: checksum mismatch")));
    EXPECT_THAT([&] { parse_identifier(bytes.substr(0, bytes.size() - 8), "w.asid"); },
                ThrowsMessage<InputError>(HasSubstr("w.asid: payload: truncated")));
    EXPECT_THAT([&] { parse_identifier(std::string("ASMLPW\0\1xxxxxxxx", 16), "w.asid"); }, ThrowsMessage<InputError>(HasSubstr("bad magic")));
  }
}

// The budgets docs/identifiers.md states: the recurrent identifier within 10 % of the feed-forward ones.
TEST(Identifier, ParameterBudgetsMatchWithinTenPercent) {
  const auto ff = constant_net(IdentifierKind::kOsi, Contract::identity()).parameter_count();
  const auto rec = constant_net(IdentifierKind::kRecurrentOsi, Contract::identity()).parameter_count();
  EXPECT_EQ(ff, 168 * 64 + 64 + 64 * 64 + 64 + 64 * 100 + 100);
  EXPECT_EQ(rec, 90 * 12 + 90 * 90 + 90 + 90 * 64 + 64 + 64 * 100 + 100);
  EXPECT_LT(std::abs(static_cast<double>(rec - ff)) / static_cast<double>(ff), 0.10);
}

TEST(Identifier, FeedForwardWindowAndRecurrentStateBothDependOnTheEvidence) {
  for (auto kind : {IdentifierKind::kOsi, IdentifierKind::kRecurrentOsi}) {
    const bool rec = kind == IdentifierKind::kRecurrentOsi;
    auto w = std::make_shared<const IdentifierWeights>(
        IdentifierWeights::init(kind, "pick_cube", rec ? 0 : 14, rec ? 90 : 0, rec ? std::vector<int>{64} : std::vector<int>{64, 64}, 3));
    IdentifierState a(w), b(w);
    Pose6 raw = Pose6::Constant(0.3), resp = Pose6::Constant(0.01);
    a.feed(raw, resp);
    b.feed(-raw, -resp);
    EXPECT_GT((a.logits() - b.logits()).norm(), 1e-4);
    a.reset();
    b.reset();
    EXPECT_LT((a.logits() - b.logits()).norm(), 1e-7);
  }
}

// The adapter sends the intent unchanged until its first estimate, then encodes it through the
// estimate: the hidden decoder of the estimated contract gives back the intent.
TEST(Identifier, AdapterPassesThroughThenActsOnItsEstimate) {
  ContractFields f = sample_contract().fields();
  f.target = "delta";
  const Contract c = Contract::make(f);
  for (auto kind : {IdentifierKind::kOsi, IdentifierKind::kRecurrentOsi}) {
    IdentifierAdapter a(std::make_shared<const IdentifierWeights>(constant_net(kind, c)), IdentifierOptions{});
    EXPECT_EQ(a.name(), identifier_kind_name(kind));
    a.begin_episode(1);
    Decoder hidden(c);
    Action intent;
    intent << 0.2, -0.1, 0.05, 0.0, 0.02, -0.03, 1.0;
    const Mat3 R = Mat3::Identity();
    for (int step = 0; step < 12; ++step) {
      const Action raw = a.encode(intent, R);
      EXPECT_FALSE(a.last_step().probe);
      if (step < 8) {
        EXPECT_TRUE(raw.isApprox(intent)) << step;
        EXPECT_FALSE(a.estimate().has_value());
      } else {
        ASSERT_TRUE(a.estimate().has_value());
        EXPECT_EQ(*a.estimate(), c);
        EXPECT_TRUE(hidden.preview(raw, R).isApprox(intent, 1e-12)) << step;
      }
      hidden.step(raw, R);
      a.observe(raw, Pose6::Constant(0.001 * step), R);
    }
  }
}

TEST(Identifier, ProbeOsiProbesFirstThenFreezesItsEstimate) {
  const Contract c = sample_contract();
  IdentifierOptions o;
  o.probe_budget = 6;
  o.freeze = true;
  IdentifierAdapter a(std::make_shared<const IdentifierWeights>(constant_net(IdentifierKind::kProbeOsi, c)), o);
  EXPECT_EQ(a.name(), "probe_osi");
  a.begin_episode(0);
  Action intent = Action::Constant(0.1);
  Decoder hidden(c);
  const Mat3 R = Mat3::Identity();
  for (int step = 0; step < 20; ++step) {
    const Action raw = a.encode(intent, R);
    if (step < 6) {
      EXPECT_TRUE(a.last_step().probe);
      EXPECT_DOUBLE_EQ(raw[step], 0.5);
      EXPECT_DOUBLE_EQ(raw.norm(), 0.5);  // one channel, the gripper never actuated
    } else {
      EXPECT_FALSE(a.last_step().probe);
      EXPECT_EQ(a.estimate().has_value(), step >= 14) << step;
    }
    if (step >= 14) {  // absolute: inverted with the replica's target
      EXPECT_TRUE(hidden.preview(raw, R).isApprox(intent, 1e-9)) << step;
    }
    hidden.step(raw, R);
    a.observe(raw, Pose6::Zero(), R);
  }
}

TEST(Identifier, RegistryBuildsIdentifiersFromWeightsOnlyAndRejectsBadOnes) {
  const std::string dir = ::testing::TempDir() + "/identifier_test_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/net.osi.asid";
  save_identifier(constant_net(IdentifierKind::kOsi, sample_contract()), path);
  auto p = resolve_method_params("osi", {{"weights", path}});
  EXPECT_EQ(p, (nlohmann::json{{"weights", path}, {"warmup", 8}}));
  EXPECT_FALSE(method_needs_pool("osi"));
  EXPECT_FALSE(method_needs_calibration("recurrent_osi"));
  const auto adapter = make_adapter("osi", p, MethodInputs{});  // no truth, no pool, no calibration
  EXPECT_EQ(adapter->name(), "osi");
  // a network of another kind, a missing file, a listed hash that does not match
  EXPECT_THAT([&] { make_adapter("recurrent_osi", resolve_method_params("recurrent_osi", {{"weights", path}}), MethodInputs{}); },
              ThrowsMessage<InputError>(HasSubstr("holds a osi network, not recurrent_osi")));
  EXPECT_THROW(make_adapter("osi", resolve_method_params("osi", {{"weights", dir + "/missing.asid"}}), MethodInputs{}), InputError);
  const std::string listed = dir + "/listed.osi.asid";
  save_identifier(constant_net(IdentifierKind::kOsi, Contract::identity()), listed);
  std::ofstream(dir + "/SHA256SUMS") << std::string(64, '0') << "  listed.osi.asid\n";
  EXPECT_THAT([&] { make_adapter("osi", resolve_method_params("osi", {{"weights", listed}}), MethodInputs{}); },
              ThrowsMessage<InputError>(HasSubstr("SHA256SUMS lists")));
  EXPECT_THAT([] { resolve_method_params("osi", {{"warmup", 0}}); }, ThrowsMessage<InputError>(HasSubstr("warmup: must be in [1, 1000]")));
  EXPECT_THAT([] { resolve_method_params("probe_osi", {{"pool", "x"}}); }, ThrowsMessage<InputError>(HasSubstr("unknown parameter")));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace actionshift::adapt
