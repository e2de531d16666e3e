// delay-aware expert: recovers the lag from its own history and keeps working under lag
#include "actionshift/core/rng.hpp"
#include "actionshift/policy/delay_aware.hpp"
#include "actionshift/policy/expert.hpp"
#include "actionshift/policy/rollout.hpp"

#include <gtest/gtest.h>

using namespace actionshift;

namespace {

Contract lag_contract(int lag) {
  ContractFields f;
  f.lag = lag;
  return Contract::make(f);
}

TEST(DelayAwareExpert, EstimatesTheLagFromItsHistory) {
  auto model = sim::EnvModel::make(sim::TaskId::kPickCube);
  for (int lag : {0, 1, 2, 4}) {
    sim::HiddenContractEnv env(model, lag_contract(lag));
    policy::DelayAwareExpert p(sim::TaskId::kPickCube);
    p.reset();
    Eigen::VectorXd obs = env.reset(derive_seed({5, 0, 1}));
    for (int t = 0; t < 12; ++t) obs = env.step(p.act(obs)).obs;
    EXPECT_EQ(p.lag_estimate(), lag);
  }
}

TEST(DelayAwareExpert, BeatsThePlainExpertUnderLag) {
  auto model = sim::EnvModel::make(sim::TaskId::kPushCube);
  policy::RolloutOptions o;
  o.episodes = 12;
  o.contract = lag_contract(2);
  int plain = 0, aware = 0;
  for (const auto& r : policy::run_episodes(*policy::make_expert(sim::TaskId::kPushCube), model, o)) plain += r.success_once;
  for (const auto& r : policy::run_episodes(policy::DelayAwareExpert(sim::TaskId::kPushCube), model, o))
    aware += r.success_once;
  EXPECT_GE(aware, 11);
  EXPECT_LE(plain, 6);
}

TEST(DelayAwareExpert, WithoutLagItIsTheExpert) {
  sim::Env env(sim::EnvModel::make(sim::TaskId::kStackCube));
  policy::DelayAwareExpert p(sim::TaskId::kStackCube, 0);
  p.reset();
  Eigen::VectorXd obs = env.reset(9);
  for (int t = 0; t < 10; ++t) {
    const Action a = p.act(obs);
    EXPECT_TRUE(a.isApprox(policy::expert_action(sim::TaskId::kStackCube, obs)));
    obs = env.step(a).obs;
  }
}

}  // namespace
