// The self-test library: every demo's verdict and diff text, abstention on an out-of-pool wiring,
// the inverted-control API (probe bounds, ordering, non-throwing twins) and what cannot be checked.
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/selftest/library.hpp"
#include "actionshift/selftest/selftest.hpp"
#include "actionshift/selftest/synthetic_robot.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>

namespace actionshift::selftest {
namespace {

using ::testing::HasSubstr;

Options synthetic_options(Strategy s) {
  Options o;  // α = 1, σ = 0.05, library pool + identity expected
  o.strategy = s;
  o.frame_rotation = FrameRotation::kIdentity;
  return o;
}

Verdict run_demo(const Contract& hidden, const Options& o, std::uint64_t seed = 20260720) {
  SelfTest st(o);
  SyntheticRobot robot(hidden, o.model, seed);
  run(st, robot);
  EXPECT_TRUE(st.done());
  return st.verdict();
}

struct DemoCase {
  const char* name;
  Status status;
  const char* reason;  // the reason must contain this
};

const DemoCase kDemos[] = {
    {"identity", Status::kPass, "every observable field resolved with high confidence and matches the expected wiring"},
    {"swapped-axes", Status::kMismatch, "channels 0 and 1 SWAPPED"},
    {"sign-flip", Status::kMismatch, "channel 3 sign FLIPPED"},
    {"miswired", Status::kMismatch, "channels 0 and 1 SWAPPED; channel 3 sign FLIPPED"},
    {"scaled", Status::kMismatch, "channel 0 scale 1->0.5"},
    {"reversed", Status::kMismatch,
     "channel routing changed at channels [0, 1, 2, 3, 4, 5]: expected permutation (0, 1, 2, 3, 4, 5), wired (5, 4, 3, 2, "
     "1, 0); channels [1, 2, 5] sign FLIPPED; channel 0 scale 1->1.5; channel 1 scale 1->1.5; channel 2 scale 1->0.5; "
     "channel 3 scale 1->2; channel 4 scale 1->0.75; channel 5 scale 1->1.25"},
    {"lagged", Status::kMismatch, "actuation lag differs: expected 0 step(s), wired 2 step(s)"},
    {"unmodeled", Status::kInconclusive, "response misspecification"},
};

class Demo : public ::testing::TestWithParam<std::tuple<DemoCase, Strategy>> {};

TEST_P(Demo, GivesTheExpectedVerdictAndDiffText) {
  const auto& [c, strategy] = GetParam();
  const auto hidden = named_contract(c.name);
  ASSERT_TRUE(hidden.has_value());
  const Verdict v = run_demo(*hidden, synthetic_options(strategy));
  EXPECT_EQ(v.status, c.status) << v.reason;
  EXPECT_EQ(v.exit_code(), static_cast<int>(c.status));
  EXPECT_THAT(v.reason, HasSubstr(c.reason));
  EXPECT_EQ(v.probe_steps, 6);
  if (c.status == Status::kMismatch) {
    EXPECT_EQ(v.reason, c.reason) << "exact diff text";
    EXPECT_EQ(v.evidence.identified, *hidden) << "in-pool wiring identified exactly";
    EXPECT_LT(v.evidence.fit_ratio, 2.0);
  }
  if (c.status == Status::kPass) {
    EXPECT_EQ(v.evidence.identified, Contract::identity());
  }
}

INSTANTIATE_TEST_SUITE_P(AllDemos, Demo,
                         ::testing::Combine(::testing::ValuesIn(kDemos),
                                            ::testing::Values(Strategy::kEntropy, Strategy::kFixed)),
                         [](const auto& info) {
                           std::string n = std::string(std::get<0>(info.param).name) + "_" +
                                           to_string(std::get<1>(info.param));
                           for (auto& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

TEST(Demo, UnmodeledAbstainsByFitRatioOverSeeds) {
  // distractor A is outside the library pool: the best hypothesis fits badly, never a guess
  for (std::uint64_t seed : {1u, 2u, 3u, 20260720u}) {
    const Verdict v = run_demo(reference::distractor_a(), synthetic_options(Strategy::kEntropy), seed);
    EXPECT_EQ(v.status, Status::kInconclusive);
    EXPECT_GT(v.evidence.fit_ratio, 4.0);
    EXPECT_TRUE(v.field_diffs.empty());
    EXPECT_THAT(v.reason, HasSubstr("outside the declared pool. Abstaining."));
  }
}

TEST(Demo, TheSameWiringInThePoolIsIdentifiedInstead) {
  Options o = synthetic_options(Strategy::kEntropy);
  o.pool = default_pool(o.expected);
  o.pool.push_back(reference::distractor_a());
  const Verdict v = run_demo(reference::distractor_a(), o);
  EXPECT_EQ(v.status, Status::kMismatch);
  EXPECT_EQ(v.evidence.identified, reference::distractor_a());
  EXPECT_LT(v.evidence.fit_ratio, 2.0);
}

TEST(Demo, IsDeterministicInTheSeed) {
  const auto o = synthetic_options(Strategy::kEntropy);
  const Verdict a = run_demo(*named_contract("miswired"), o, 7), b = run_demo(*named_contract("miswired"), o, 7),
                c = run_demo(*named_contract("miswired"), o, 8);
  EXPECT_EQ(a.evidence.fit_ratio, b.evidence.fit_ratio);
  EXPECT_EQ(a.displacement, b.displacement);
  EXPECT_NE(a.evidence.fit_ratio, c.evidence.fit_ratio);
}

// ---- library and pool

TEST(Library, HoldsTheReferencePoolInOrder) {
  const auto lib = library();
  ASSERT_EQ(lib.size(), 8u);
  const char* names[] = {"identity", "swapped-axes", "sign-flip", "miswired", "scaled", "relabeled", "reversed", "lagged"};
  for (std::size_t i = 0; i < lib.size(); ++i) EXPECT_EQ(lib[i].name, names[i]);
  EXPECT_EQ(lib[0].contract, Contract::identity());
  EXPECT_EQ(lib[7].contract.lag(), 2);
  const auto d = demos();
  ASSERT_EQ(d.size(), 8u);
  EXPECT_EQ(d.back().name, "unmodeled");
  EXPECT_EQ(d.back().contract.sha256(), "44a1aa9652f9ac2788cfa02a54665f9ed62d588fe8ccf21a334cd3b67a4d28d7");
  EXPECT_FALSE(named_contract("nonsense").has_value());
}

TEST(Library, ExpectedIsAppendedOnceAndTheTruthNever) {
  EXPECT_EQ(default_pool(Contract::identity()).size(), 8u);
  const auto p = default_pool(reference::oracle_contract());
  ASSERT_EQ(p.size(), 9u);
  EXPECT_EQ(p.back(), reference::oracle_contract());
  Options o;
  o.expected = reference::oracle_contract();
  SelfTest st(o);
  EXPECT_EQ(st.pool().size(), 9u);
  o.pool = {reference::oracle_contract(), Contract::identity()};
  EXPECT_EQ(SelfTest(o).pool().size(), 2u);
}

TEST(SelfTest, ANonIdentityExpectationPassesWhenTheRobotMatchesIt) {
  Options o = synthetic_options(Strategy::kEntropy);
  o.expected = *named_contract("miswired");
  EXPECT_EQ(run_demo(*named_contract("miswired"), o).status, Status::kPass);
  const Verdict v = run_demo(Contract::identity(), o);
  EXPECT_EQ(v.status, Status::kMismatch);
  EXPECT_EQ(v.reason, "channels 0 and 1 SWAPPED; channel 3 sign FLIPPED");
}

// ---- the inverted control loop

TEST(SelfTest, ProbesAreBoundedAndNeverActuateTheGripper) {
  for (Strategy s : {Strategy::kEntropy, Strategy::kFixed}) {
    Options o = synthetic_options(s);
    o.amplitude = 0.3;
    o.budget = 15;
    SelfTest st(o);
    SyntheticRobot robot(*named_contract("reversed"), o.model, 3);
    st.begin(robot.pose());
    int n = 0;
    while (auto raw = st.next_probe()) {
      EXPECT_LE(raw->head<6>().cwiseAbs().maxCoeff(), 0.3 + 1e-15);
      EXPECT_GT(raw->head<6>().cwiseAbs().maxCoeff(), 0.0);
      EXPECT_EQ((*raw)[kGripper], 0.0);
      EXPECT_EQ(*st.next_probe(), *raw) << "asking again before observe() repeats the probe";
      robot.send(*raw);
      st.observe(robot.pose());
      ++n;
    }
    EXPECT_EQ(n, 15);
    EXPECT_TRUE(st.done());
    EXPECT_FALSE(st.next_probe().has_value());
    const Verdict v = st.verdict();
    EXPECT_EQ(v.amplitude, 0.3);
    EXPECT_GT(v.displacement, 0.0);
    EXPECT_GE(v.displacement, v.max_excursion);
    EXPECT_THAT(v.safety_statement("m"), HasSubstr("|action| <= 0.3 per pose channel, gripper never actuated"));
  }
}

// Options::gripper: every probe's gripper channel is the command that holds the fingers where begin()
// found them, under the expected wiring's polarity; the report says so and shows the travel
TEST(SelfTest, ProbesHoldTheFingersWhereTheyStarted) {
  struct Case {
    Eigen::Vector2d fingers;
    bool expected_inverted;
    double hold;
  };
  for (const Case& c : {Case{{0.04, 0.04}, false, 1.0}, Case{{0.04, 0.04}, true, -1.0}, Case{{0.015, 0.015}, false, 0.0},
                        Case{{0.0275, 0.0275}, true, -0.5}, Case{{0.09, 0.08}, false, 1.0}}) {
    Options o = synthetic_options(Strategy::kEntropy);
    o.gripper = GripperMap{0.015, 0.025};  // the simulator's controller
    if (c.expected_inverted) {
      ContractFields f;
      f.gripper_inverted = true;
      o.expected = Contract::make(f);
    }
    SelfTest st(o);
    SyntheticRobot robot(o.expected, o.model, 3);
    TcpPose start = robot.pose();
    start.fingers = c.fingers;
    st.begin(start);
    int n = 0;
    while (auto raw = st.next_probe()) {
      EXPECT_NEAR((*raw)[kGripper], c.hold, 1e-12) << "probe " << n;
      robot.send(*raw);
      TcpPose p = robot.pose();
      p.fingers = c.fingers;  // held: the fingers did not move
      st.observe(p);
      ++n;
    }
    const Verdict v = st.verdict();
    ASSERT_TRUE(v.gripper_hold.has_value());
    EXPECT_NEAR(*v.gripper_hold, c.hold, 1e-12);
    EXPECT_EQ(v.finger_travel, 0.0);
    EXPECT_THAT(v.safety_statement("m"), HasSubstr("gripper held at its start position (raw gripper command"));
    EXPECT_THAT(v.safety_statement("m"), HasSubstr("Finger travel while probing: 0.0000 m (held)."));
  }
  // no finger positions at begin(): nothing to hold, the channel is 0 and the report says so
  Options o = synthetic_options(Strategy::kFixed);
  o.gripper = GripperMap{0.015, 0.025};
  SelfTest st(o);
  SyntheticRobot robot(Contract::identity(), o.model, 3);
  st.begin(robot.pose());
  EXPECT_EQ((*st.next_probe())[kGripper], 0.0);
  EXPECT_FALSE(st.verdict().gripper_hold.has_value());
  EXPECT_THAT(st.verdict().safety_statement("m"), HasSubstr("gripper never actuated"));
  // travel while holding is reported as movement, never as "held"
  Verdict moved = st.verdict();
  moved.gripper_hold = 1.0;
  moved.finger_travel = 0.048;
  EXPECT_THAT(moved.safety_statement("m"), HasSubstr("0.0480 m (the fingers moved"));
  // a gripper map must be usable
  std::string err;
  o.gripper = GripperMap{0.015, 0.0};
  EXPECT_FALSE(validate(o, &err));
  EXPECT_THAT(err, HasSubstr("gripper.gain"));
}

TEST(SelfTest, EntropyProbesReturnTowardsTheStart) {
  // every channel's summed raw command stays within ±amplitude, so a delta-wired TCP cannot drift
  Options o = synthetic_options(Strategy::kEntropy);
  o.budget = 40;
  SelfTest st(o);
  SyntheticRobot robot(Contract::identity(), o.model, 5);
  st.begin(robot.pose());
  Pose6 sum = Pose6::Zero();
  while (auto raw = st.next_probe()) {
    sum += raw->head<6>();
    EXPECT_LE(sum.cwiseAbs().maxCoeff(), 0.5 + 1e-12);
    robot.send(*raw);
    st.observe(robot.pose());
  }
  EXPECT_EQ(st.verdict().status, Status::kPass);
  EXPECT_LE(st.verdict().max_excursion, 0.5 * std::sqrt(3.0) + 0.5);  // one pulse per axis plus noise
  o.return_balanced = false;  // the reference's greedy choice: repeats the most informative pulse
  SelfTest greedy(o);
  SyntheticRobot robot2(Contract::identity(), o.model, 5);
  greedy.begin(robot2.pose());
  Pose6 sum2 = Pose6::Zero();
  while (auto raw = greedy.next_probe()) {
    sum2 += raw->head<6>();
    robot2.send(*raw);
    greedy.observe(robot2.pose());
  }
  EXPECT_GT(sum2.cwiseAbs().maxCoeff(), 0.5);
}

TEST(SelfTest, NoProbeSaturatesTheControllerUnderAPlausibleWiring) {
  // absolute target, scale 2 on channel 0: +0.5 then −0.5 on raw channel 0 would decode to a −2 step
  ContractFields f;
  f.target = "absolute";
  f.scale = {2.0, 1.0, 1.0, 1.0, 1.0, 1.0};
  const Contract hidden = Contract::make(f);
  Options o = synthetic_options(Strategy::kEntropy);
  o.pool = default_pool(o.expected);
  o.pool.push_back(hidden);
  o.budget = 20;
  SelfTest st(o);
  SyntheticRobot robot(hidden, o.model, 9);
  st.begin(robot.pose());
  while (auto raw = st.next_probe()) {
    robot.send(*raw);
    EXPECT_LE(robot.last_canonical().head<3>().cwiseAbs().maxCoeff(), 1.0 + 1e-9);
    EXPECT_LE(robot.last_canonical().segment<3>(3).norm(), 1.0 + 1e-9);
    st.observe(robot.pose());
  }
  EXPECT_EQ(st.verdict().evidence.identified, hidden);
}

TEST(SelfTest, FixedStrategySendsTheReferencePulses) {
  Options o = synthetic_options(Strategy::kFixed);
  o.budget = 8;
  SelfTest st(o);
  st.begin({});
  for (int k = 0; k < 8; ++k) {
    const auto raw = st.next_probe();
    ASSERT_TRUE(raw);
    EXPECT_EQ(*raw, adapt::fixed_probe_pulse(k, 0.5));
    st.observe({});
  }
}

TEST(SelfTest, ResponsesComeFromConsecutivePoses) {
  // a robot that moves exactly α ⊙ canonical: the MAP replay fits perfectly
  Options o = synthetic_options(Strategy::kFixed);
  o.model.sigma.fill(1e-3);
  adapt::ResponseModel exact = o.model;
  exact.sigma.fill(0.0);
  SelfTest st(o);
  SyntheticRobot robot(*named_contract("sign-flip"), exact, 1);
  run(st, robot);
  const Verdict v = st.verdict();
  EXPECT_EQ(v.evidence.identified, *named_contract("sign-flip"));
  EXPECT_LT(v.evidence.fit_ratio, 1e-12);
}

TEST(SelfTest, MisuseIsReportedNotIgnored) {
  SelfTest st(Options{});
  EXPECT_THROW(st.next_probe(), std::logic_error);
  std::string err;
  EXPECT_FALSE(st.try_observe({}, &err));
  EXPECT_THAT(err, HasSubstr("without an outstanding probe"));
  EXPECT_THROW(st.observe({}), std::logic_error);
  TcpPose bad;
  bad.position[0] = std::nan("");
  EXPECT_FALSE(st.try_begin(bad, &err));
  EXPECT_THAT(err, HasSubstr("TCP pose must be finite"));
  EXPECT_THROW(st.begin(bad), std::invalid_argument);
  st.begin({});
  ASSERT_TRUE(st.next_probe());
  TcpPose zero_q;
  zero_q.quaternion.setZero();
  EXPECT_FALSE(st.try_observe(zero_q, &err));
  EXPECT_THAT(err, HasSubstr("quaternion must be non-zero"));
  EXPECT_EQ(st.probes_observed(), 0) << "a rejected sample is not evidence";
  // finite but absurd (a unit error): its squares used to overflow the belief into NaN confidences
  TcpPose far;
  far.position[0] = 1e200;
  EXPECT_FALSE(st.try_observe(far, &err));
  EXPECT_THAT(err, HasSubstr("beyond 1e6 m"));
  TcpPose far_fingers;
  far_fingers.fingers = Eigen::Vector2d(0.04, 1e9);
  EXPECT_FALSE(st.try_observe(far_fingers, &err));
  EXPECT_EQ(st.probes_observed(), 0);
  EXPECT_TRUE(st.try_observe({}, &err));
  EXPECT_EQ(st.probes_observed(), 1);
}

TEST(SelfTest, NoEvidenceNeverPasses) {
  Options o;
  o.pool = {Contract::identity()};  // a one-member pool is trivially "confident"
  SelfTest st(o);
  st.begin({});
  const Verdict v = st.verdict();
  EXPECT_EQ(v.status, Status::kInconclusive);
  EXPECT_EQ(v.probe_steps, 0);
}

// ---- options: one validator behind the throwing and the non-throwing path

TEST(Options, InvalidOptionsGiveTheSameMessageOnBothPaths) {
  struct Case {
    void (*edit)(Options&);
    const char* message;
  };
  const Case cases[] = {
      {[](Options& o) { o.budget = 0; }, "selftest options: budget must be in [1, 10000] (got 0)"},
      {[](Options& o) { o.amplitude = 1.5; }, "selftest options: amplitude must be in (0, 1] (got 1.5)"},
      {[](Options& o) { o.amplitude = std::nan(""); }, "amplitude must be in (0, 1]"},
      {[](Options& o) { o.confidence_floor = 0.0; }, "confidence_floor must be in (0, 1] (got 0)"},
      {[](Options& o) { o.misspec_ratio = -1; }, "misspec_ratio must be finite and positive (got -1)"},
      {[](Options& o) { o.model.alpha[2] = 0; }, "model.alpha[2] must be finite and non-zero (got 0)"},
      {[](Options& o) { o.model.sigma[5] = 0; }, "model.sigma[5] must be finite and positive (got 0)"},
  };
  for (const auto& c : cases) {
    Options o;
    c.edit(o);
    std::string err;
    EXPECT_FALSE(validate(o, &err));
    EXPECT_THAT(err, HasSubstr(c.message));
    std::string err2;
    EXPECT_FALSE(SelfTest::create(o, &err2).has_value());
    EXPECT_EQ(err, err2);
    EXPECT_THAT([&] { SelfTest st(o); }, ::testing::ThrowsMessage<std::invalid_argument>(::testing::StrEq(err)));
  }
  std::string err;
  EXPECT_TRUE(validate(Options{}, &err));
  EXPECT_TRUE(SelfTest::create(Options{}, nullptr).has_value());
}

// ---- what cannot be checked

std::vector<std::string> unchecked_names(const Verdict& v) {
  std::vector<std::string> n;
  for (const auto& u : v.unchecked) n.push_back(u.field);
  return n;
}

TEST(Unchecked, GripperIsAlwaysListedAndFrameUnderIdentityRotation) {
  const Verdict v = run_demo(Contract::identity(), synthetic_options(Strategy::kEntropy));
  EXPECT_THAT(unchecked_names(v), ::testing::ElementsAre("gripper_inverted", "frame"));
  EXPECT_THAT(v.unchecked[1].reason, HasSubstr("tool frame under identity rotation"));
}

TEST(Unchecked, FrameIsCheckedUnderAMeasuredRotationFarFromIdentity) {
  // a robot whose tool points down (180° about x) and decodes tool-frame commands with its live
  // rotation; response = α ⊙ canonical, exactly, with small rotation gains
  Options o;
  o.frame_rotation = FrameRotation::kLive;
  o.model.alpha = {1, 1, 1, 0.1, 0.1, 0.1};
  o.model.sigma.fill(0.02);
  const Contract tool = reference::with(Contract::identity(), "delta", "tool", 0);
  o.pool = {Contract::identity(), tool};
  SelfTest st(o);
  TcpPose pose;
  pose.quaternion = {0.0, 1.0, 0.0, 0.0};
  st.begin(pose);
  Decoder dec(tool);
  while (auto raw = st.next_probe()) {
    Eigen::Quaterniond q(pose.quaternion[0], pose.quaternion[1], pose.quaternion[2], pose.quaternion[3]);
    const Action c = dec.step(*raw, q.toRotationMatrix());
    pose.position += c.head<3>();
    const Vec3 rv = 0.1 * c.segment<3>(3);
    q = (Eigen::Quaterniond(Eigen::AngleAxisd(rv.norm(), rv.normalized())) * q).normalized();
    pose.quaternion = {q.w(), q.x(), q.y(), q.z()};
    st.observe(pose);
  }
  const Verdict v = st.verdict();
  EXPECT_THAT(unchecked_names(v), ::testing::ElementsAre("gripper_inverted"));
  EXPECT_EQ(v.status, Status::kMismatch);
  EXPECT_EQ(v.reason, "reference frame differs: expected base, wired tool");
  EXPECT_LT(v.evidence.fit_ratio, 1e-6);
}

TEST(Unchecked, FrameIsNotCheckedWhileTheMeasuredRotationStaysNearIdentity) {
  Options o;
  o.frame_rotation = FrameRotation::kLive;
  SelfTest st(o);
  SyntheticRobot robot(Contract::identity(), o.model, 1);  // starts at identity orientation
  run(st, robot);
  const Verdict v = st.verdict();
  EXPECT_THAT(unchecked_names(v), ::testing::ElementsAre("gripper_inverted", "frame"));
  EXPECT_THAT(v.unchecked[1].reason, HasSubstr("near-)identity rotation"));
}

TEST(Unchecked, ScaleIsNotCheckedWhenTheIdentifiedTargetIsAbsolute) {
  Options o = synthetic_options(Strategy::kEntropy);
  ContractFields f;
  f.target = "absolute";
  f.scale = {2.0, 1.0, 1.0, 1.0, 1.0, 1.0};
  const Contract hidden = Contract::make(f);
  o.pool = default_pool(o.expected);
  o.pool.push_back(hidden);
  const Verdict v = run_demo(hidden, o);
  EXPECT_EQ(v.evidence.identified, hidden);
  EXPECT_THAT(unchecked_names(v), ::testing::Contains("scale"));
  EXPECT_EQ(v.status, Status::kMismatch);
  EXPECT_EQ(v.reason, "target encoding differs: expected delta, wired absolute") << "no scale sentence";
}

}  // namespace
}  // namespace actionshift::selftest
