// scripted experts: competence on a few episodes, state-only interface
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/policy/expert.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/policy/rollout.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

using namespace actionshift;
using ::testing::HasSubstr;

namespace {

int successes(const policy::Policy& p, sim::TaskId task, int episodes, std::uint64_t seed = 7) {
  policy::RolloutOptions o;
  o.seed = seed;
  o.episodes = episodes;
  int s = 0;
  for (const auto& r : policy::run_episodes(p, sim::EnvModel::make(task), o)) s += r.success_once ? 1 : 0;
  return s;
}

class ExpertTask : public ::testing::TestWithParam<sim::TaskId> {};

TEST_P(ExpertTask, SolvesNearlyEveryEpisode) {
  auto e = policy::make_expert(GetParam());
  EXPECT_GE(successes(*e, GetParam(), 16), 15) << sim::task_name(GetParam());
}

INSTANTIATE_TEST_SUITE_P(CubeTasks, ExpertTask,
                         ::testing::Values(sim::TaskId::kPickCube, sim::TaskId::kPushCube, sim::TaskId::kPullCube,
                                           sim::TaskId::kStackCube),
                         [](const auto& info) { return std::string(sim::task_name(info.param)); });

TEST(Expert, IsAPureFunctionOfTheObservation) {
  sim::Env env(sim::EnvModel::make(sim::TaskId::kPickCube));
  const Eigen::VectorXd obs = env.reset(3);
  const Action a = policy::expert_action(sim::TaskId::kPickCube, obs);
  EXPECT_TRUE(a.isApprox(policy::expert_action(sim::TaskId::kPickCube, obs)));
  // it reads obj_pose by name: a cube on the other side of the tcp flips the x command
  const auto& layout = sim::observation_layout(sim::TaskId::kPickCube);
  const int tcp = layout.at("tcp_pose").offset, cube = layout.at("obj_pose").offset;
  Eigen::VectorXd ahead = obs, behind = obs;
  ahead(cube) = obs(tcp) + 0.2;
  behind(cube) = obs(tcp) - 0.2;
  EXPECT_GT(policy::expert_action(sim::TaskId::kPickCube, ahead)(0), 0.5);
  EXPECT_LT(policy::expert_action(sim::TaskId::kPickCube, behind)(0), -0.5);
  EXPECT_LE(a.head<3>().cwiseAbs().maxCoeff(), 1.0);
  EXPECT_LE(a.segment<3>(3).norm(), 1.0 + 1e-12);
}

TEST(Expert, RejectsAWrongSizedObservation) {
  auto e = policy::make_expert(sim::TaskId::kPushCube);
  EXPECT_THAT([&] { e->act(Eigen::VectorXd::Zero(42)); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("observation has 42 entries, expected 35")));
}

TEST(Expert, HashIdentifiesVersionAndTask) {
  auto a = policy::make_expert(sim::TaskId::kPickCube), b = policy::make_expert(sim::TaskId::kPushCube);
  EXPECT_EQ(a->sha256(), sha256_hex("actionshift-expert-v3/pick_cube"));
  EXPECT_NE(a->sha256(), b->sha256());
  EXPECT_EQ(a->name(), "expert");
}

TEST(Registry, UnknownBackboneIsAnInputError) {
  EXPECT_THAT([] { policy::make_policy("sac", sim::TaskId::kPickCube); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("unknown backbone 'sac'")));
  // ppo is a known backbone whose weight file must exist (none is committed for pick_cube)
  policy::RegistryOptions none;
  none.backbones_dir = "/nonexistent";
  EXPECT_THAT([&none] { policy::make_policy("ppo", sim::TaskId::kPickCube, none); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("/nonexistent/pick_cube.ppo.asmlp")));
  EXPECT_THAT([] { policy::make_policy("external:", sim::TaskId::kPickCube); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("needs a command")));
}

TEST(Rollout, ResultsDoNotDependOnThreadCount) {
  auto e = policy::make_expert(sim::TaskId::kStackCube);
  auto model = sim::EnvModel::make(sim::TaskId::kStackCube);
  policy::RolloutOptions o;
  o.episodes = 6;
  o.threads = 1;
  const auto one = policy::run_episodes(*e, model, o);
  o.threads = 3;
  const auto three = policy::run_episodes(*e, model, o);
  ASSERT_EQ(one.size(), three.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    EXPECT_EQ(one[k].env_seed, derive_seed({o.seed, 0, static_cast<std::uint64_t>(k)}));
    EXPECT_EQ(one[k].success_once, three[k].success_once);
    EXPECT_EQ(one[k].episode_return, three[k].episode_return);
  }
}

}  // namespace
