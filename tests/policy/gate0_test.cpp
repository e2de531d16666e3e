// Gate 0: the reference's statistics and reason strings (reference 8.1, 15 item 16), and a smoke
// run compared with the committed expected verdict
#include "actionshift/policy/gate0.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/sim/robot_description.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>

using namespace actionshift;
using ::testing::HasSubstr;

namespace {

TEST(Gate0, WilsonMatchesTheReference) {
  const auto w = policy::wilson(50, 100);
  EXPECT_NEAR(w.lower, 0.4038315304, 1e-10);
  EXPECT_NEAR(w.upper, 0.5961684696, 1e-10);
  EXPECT_THAT([] { policy::wilson(0, 0); }, ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("at least one episode is required")));
}

TEST(Gate0, ParityPassesByTwoPointsOrByOverlapOtherwiseFails) {
  const auto two = policy::gate0_parity(75, 100, 73, 100);
  EXPECT_TRUE(two.two_point_rule);
  EXPECT_TRUE(two.passed);
  const auto overlap = policy::gate0_parity(6, 10, 8, 10);
  EXPECT_FALSE(overlap.two_point_rule);
  EXPECT_TRUE(overlap.overlap_rule);
  EXPECT_TRUE(overlap.passed);
  const auto fail = policy::gate0_parity(90, 100, 50, 100);
  EXPECT_FALSE(fail.passed);
  EXPECT_EQ(fail.reason, "absolute success difference 0.4000 exceeds 0.0200 and CIs do not overlap");
}

TEST(Gate0, CompetenceReasonsAndFloors) {
  EXPECT_EQ(policy::gate0_competence(40, 100, 0.5, policy::Gate0Rule::kPointEstimate).reason,
            "success 0.4000 below floor 0.5000");
  const auto w = policy::gate0_competence(55, 100, 0.5, policy::Gate0Rule::kWilsonLower);
  EXPECT_FALSE(w.passed);
  EXPECT_THAT(w.reason, HasSubstr("success Wilson lower bound 0.4524 below floor 0.5000"));
  EXPECT_TRUE(policy::gate0_competence(55, 100, 0.5, policy::Gate0Rule::kPointEstimate).passed);
  EXPECT_DOUBLE_EQ(policy::gate0_floor(sim::TaskId::kPegInsertionSide), 0.2);
  EXPECT_DOUBLE_EQ(policy::gate0_floor(sim::TaskId::kPickCube), 0.5);
}

TEST(Gate0, ExcludesAPolicyThatDoesNothing) {
  // a zero-action policy: the cube never reaches the goal
  struct Idle final : policy::Policy {
    void reset() override {}
    Action act(const Eigen::Ref<const Eigen::VectorXd>&) override { return Action::Zero(); }
    std::string name() const override { return "idle"; }
    std::string sha256() const override { return std::string(64, '0'); }
    sim::TaskId task() const override { return sim::TaskId::kPushCube; }
    std::unique_ptr<policy::Policy> clone() const override { return std::make_unique<Idle>(); }
  } idle;
  policy::Gate0Run run;
  run.episodes = 4;
  const auto v = policy::run_gate0(idle, run);
  EXPECT_EQ(v.decision, "exclude");
  EXPECT_THAT(v.reason, HasSubstr("competence: success Wilson lower bound 0.0000 below floor 0.5000"));
  EXPECT_TRUE(v.identity_parity.passed);
}

TEST(Gate0, AHorizonOverrideSetsTheEpisodeLengthAndIsRecordedOnlyWhenGiven) {
  // an idle policy that counts its steps, shared by every clone: each episode runs the full horizon
  struct Counting final : policy::Policy {
    std::shared_ptr<std::atomic<int>> steps = std::make_shared<std::atomic<int>>(0);
    void reset() override {}
    Action act(const Eigen::Ref<const Eigen::VectorXd>&) override {
      ++*steps;
      return Action::Zero();
    }
    std::string name() const override { return "counting"; }
    std::string sha256() const override { return std::string(64, '0'); }
    sim::TaskId task() const override { return sim::TaskId::kPushCube; }
    std::unique_ptr<policy::Policy> clone() const override { return std::make_unique<Counting>(*this); }
  } counting;
  policy::Gate0Run run;
  run.episodes = 2;
  run.threads = 1;
  const auto task_default = policy::run_gate0(counting, run);
  EXPECT_EQ(counting.steps->load(), 2 * 2 * 50);  // unwrapped and identity-wrapped, push_cube's 50 steps
  EXPECT_FALSE(policy::gate0_to_json({task_default}).at("cells").at("counting/push_cube").contains("horizon"));
  *counting.steps = 0;
  run.horizon = 7;
  const auto seven = policy::run_gate0(counting, run);
  EXPECT_EQ(counting.steps->load(), 2 * 2 * 7);
  EXPECT_EQ(policy::gate0_to_json({seven}).at("cells").at("counting/push_cube").at("horizon"), 7);
  run.horizon = -1;
  EXPECT_THAT([&] { policy::check_gate0_run(run); }, ::testing::ThrowsMessage<InputError>(HasSubstr("horizon")));
  run.horizon = sim::kMaxHorizon + 1;
  EXPECT_THAT([&] { policy::run_gate0(counting, run); }, ::testing::ThrowsMessage<InputError>(HasSubstr("horizon")));
}

TEST(Gate0, AVerdictOnAUserRobotNamesItsHashInTheCellKeyAndCell) {
  // counts only: the verdict file of the embedded Panda is unchanged; a user robot's verdict is
  // another cell (its id carries the description's hash) that records the full hash
  std::vector<policy::EpisodeOutcome> all(10);
  for (auto& e : all) e.success_once = e.success_at_end = true;
  policy::Gate0Verdict v = policy::gate0_verdict("expert", std::string(64, 'b'), sim::TaskId::kPickCube, all, all, 0.5,
                                                 policy::Gate0Rule::kWilsonLower);
  const nlohmann::json embedded = policy::gate0_to_json({v});
  ASSERT_TRUE(embedded.at("cells").contains("expert/pick_cube"));
  EXPECT_FALSE(embedded.at("cells").at("expert/pick_cube").contains("robot"));
  v.robot_sha256 = "0123456789ab" + std::string(52, 'f');
  const nlohmann::json user = policy::gate0_to_json({v});
  ASSERT_EQ(user.at("cells").size(), 1u);
  ASSERT_TRUE(user.at("cells").contains("expert/pick_cube@robot:0123456789ab")) << user.dump();
  EXPECT_EQ(user.at("cells").at("expert/pick_cube@robot:0123456789ab").at("robot").at("sha256"), v.robot_sha256);
  // a run with a robot description must name it
  policy::Gate0Run run;
  run.episodes = 1;
  run.robot = std::make_shared<const sim::RobotDescription>(sim::panda_description());
  EXPECT_THAT([&] { policy::run_gate0(*policy::make_policy("expert", sim::TaskId::kPickCube), run); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("robot_sha256")));
}

// Smoke: 20 episodes of a backbone compared with configs/gates/gate0/smoke/<backbone>.<task>.json.
// Decision and verdict must match; success counts may move by at most 2 episodes (physics tuning).
void check_smoke(const std::string& backbone, sim::TaskId task) {
  const std::string file = std::string(ACTIONSHIFT_SOURCE_DIR) + "/configs/gates/gate0/smoke/" + backbone + "." +
                           std::string(sim::task_name(task)) + ".json";
  std::ifstream f(file);
  ASSERT_TRUE(f) << file;
  const nlohmann::json expected = nlohmann::json::parse(f);
  const std::string key = backbone + "/" + std::string(sim::task_name(task));
  const nlohmann::json& e = expected.at("cells").at(key);
  policy::Gate0Run run;
  run.episodes = e.at("episodes").get<std::int64_t>();
  run.seed = e.at("seed").get<std::uint64_t>();
  const auto v = policy::run_gate0(*policy::make_policy(backbone, task), run);
  const nlohmann::json actual = policy::gate0_to_json({v}).at("cells").at(key);
  EXPECT_EQ(actual.at("decision"), e.at("decision")) << file;
  EXPECT_EQ(actual.at("verdict"), e.at("verdict")) << file;
  EXPECT_EQ(actual.at("backbone_sha256"), e.at("backbone_sha256")) << file;
  EXPECT_NEAR(actual.at("competence").at("interval").at("successes").get<double>(),
              e.at("competence").at("interval").at("successes").get<double>(), 2.0);
  EXPECT_NEAR(actual.at("identity_parity").at("wrapped").at("successes").get<double>(),
              e.at("identity_parity").at("wrapped").at("successes").get<double>(), 2.0);
}

TEST(Gate0Smoke, ExpertPickCubeMatchesCommittedVerdict) { check_smoke("expert", sim::TaskId::kPickCube); }
TEST(Gate0Smoke, MlpPushCubeMatchesCommittedVerdict) { check_smoke("mlp", sim::TaskId::kPushCube); }

}  // namespace
