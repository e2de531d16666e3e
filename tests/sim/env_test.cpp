// env: seeded resets, determinism across instances and threads, safety flags, grasp detection
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/grasp_script.hpp"

#include "actionshift/core/rng.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <thread>
#include <vector>

namespace actionshift::sim {
namespace {

// a fixed pseudo-random action sequence (with gripper closes) touching every channel
std::vector<Action> action_sequence(int n, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<Action> out;
  for (int i = 0; i < n; ++i) {
    Action a;
    for (int k = 0; k < 6; ++k) a(k) = rng.uniform(-0.6, 0.6);
    a(2) -= 0.3;
    a(6) = (i / 6) % 2 ? -1.0 : 1.0;
    out.push_back(a);
  }
  return out;
}

std::vector<double> rollout(const std::shared_ptr<const EnvModel>& model, std::uint64_t seed, int steps) {
  Env env(model);
  std::vector<double> trace;
  const Eigen::VectorXd& o0 = env.reset(seed);
  trace.insert(trace.end(), o0.data(), o0.data() + o0.size());
  for (const Action& a : action_sequence(steps, seed ^ 0x5a5a)) {
    const StepResult& r = env.step(a);
    trace.insert(trace.end(), r.obs.data(), r.obs.data() + r.obs.size());
    trace.push_back(r.reward);
    if (r.episode_over()) break;
  }
  return trace;
}

bool byte_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

TEST(Env, ResetIsAPureFunctionOfTheSeedWhateverCameBefore) {
  for (TaskId task : all_tasks()) {
    const auto model = EnvModel::make(task);
    Env a(model), b(model);
    const Eigen::VectorXd first = a.reset(123);
    // b runs a different episode first, then the same seed
    b.reset(999);
    for (const Action& act : action_sequence(8, 1)) b.step(act);
    const Eigen::VectorXd second = b.reset(123);
    ASSERT_EQ(first.size(), model->layout().size());
    EXPECT_EQ(std::memcmp(first.data(), second.data(), sizeof(double) * static_cast<std::size_t>(first.size())), 0)
        << task_name(task);
    EXPECT_FALSE(first.isApprox(a.reset(124))) << task_name(task);
  }
}

TEST(Env, SameSeedGivesAByteIdenticalTrajectory) {
  for (TaskId task : {TaskId::kPickCube, TaskId::kStackCube, TaskId::kPegInsertionSide}) {
    const auto model = EnvModel::make(task);
    EXPECT_TRUE(byte_equal(rollout(model, 77, 30), rollout(model, 77, 30))) << task_name(task);
    EXPECT_FALSE(byte_equal(rollout(model, 77, 5), rollout(model, 78, 5))) << task_name(task);
  }
}

TEST(Env, TwoThreadsGiveTheSameResultsAsOne) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  const std::vector<std::uint64_t> seeds = {1, 2, 3, 4};
  std::vector<std::vector<double>> serial;
  for (auto s : seeds) serial.push_back(rollout(model, s, 25));
  std::vector<std::vector<double>> threaded(seeds.size());
  std::thread t0([&] { for (std::size_t i = 0; i < seeds.size(); i += 2) threaded[i] = rollout(model, seeds[i], 25); });
  std::thread t1([&] { for (std::size_t i = 1; i < seeds.size(); i += 2) threaded[i] = rollout(model, seeds[i], 25); });
  t0.join();
  t1.join();
  for (std::size_t i = 0; i < seeds.size(); ++i) EXPECT_TRUE(byte_equal(serial[i], threaded[i])) << "seed " << seeds[i];
}

TEST(Env, InitialStatesFollowTheSpawnDistributions) {
  const auto pick = EnvModel::make(TaskId::kPickCube);
  Env env(pick);
  const auto& l = pick->layout();
  for (std::uint64_t seed = 0; seed < 30; ++seed) {
    const Eigen::VectorXd o = env.reset(seed);
    const Eigen::Vector3d cube = o.segment<3>(l.at("obj_pose").offset);
    const Eigen::Vector3d goal = o.segment<3>(l.at("goal_pos").offset);
    EXPECT_LE(cube.head<2>().cwiseAbs().maxCoeff(), 0.1);
    EXPECT_NEAR(cube.z(), 0.02, 1e-9);
    EXPECT_LE(goal.head<2>().cwiseAbs().maxCoeff(), 0.1);
    EXPECT_GE(goal.z(), 0.02);
    EXPECT_LE(goal.z(), 0.32);
    EXPECT_DOUBLE_EQ(o(7), 0.04);  // fingers open
    EXPECT_DOUBLE_EQ(o(8), 0.04);
    EXPECT_LT((o.head<7>() - pick->rest_qpos().head<7>()).cwiseAbs().maxCoeff(), 0.1);  // 5 sigma of 0.02
    const Eigen::Vector3d tcp = o.segment<3>(l.at("tcp_pose").offset);
    EXPECT_LT(tcp.norm(), 0.2 - 0.0302 + 0.05);
  }
  const auto push = EnvModel::make(TaskId::kPushCube);
  Env pe(push);
  const Eigen::VectorXd o = pe.reset(5);
  const auto& pl = push->layout();
  EXPECT_NEAR(o(pl.at("goal_pos").offset) - o(pl.at("obj_pose").offset), 0.2, 1e-12);
  const auto pull = EnvModel::make(TaskId::kPullCube);
  Env ue(pull);
  const Eigen::VectorXd u = ue.reset(5);
  EXPECT_NEAR(u(pl.at("goal_pos").offset) - u(pl.at("obj_pose").offset), -0.2, 1e-12);
  const auto stack = EnvModel::make(TaskId::kStackCube);
  Env se(stack);
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const Eigen::VectorXd s = se.reset(seed);
    const Eigen::Vector3d ab = s.segment<3>(stack->layout().at("cubeA_to_cubeB_pos").offset);
    EXPECT_GT(ab.head<2>().norm(), 0.0585);
  }
  const auto peg = EnvModel::make(TaskId::kPegInsertionSide);
  Env ge(peg);
  const Eigen::VectorXd g = ge.reset(3);
  const auto& gl = peg->layout();
  const double half_len = g(gl.at("peg_half_size").offset), r = g(gl.at("peg_half_size").offset + 1);
  EXPECT_GE(half_len, 0.085);
  EXPECT_LE(half_len, 0.125);
  EXPECT_GE(r, 0.015);
  EXPECT_LE(r, 0.025);
  EXPECT_NEAR(g(gl.at("box_hole_radius").offset), r + 0.003, 1e-12);
  EXPECT_NEAR(g(gl.at("peg_pose").offset + 2), r, 1e-6);  // resting on the table
}

TEST(Env, ObservationFieldsAreConsistent) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  Env env(model);
  env.reset(9);
  const auto& l = model->layout();
  const StepResult& r = env.step(Action::Zero());
  const Eigen::VectorXd& o = r.obs;
  const Eigen::Vector3d tcp = o.segment<3>(l.at("tcp_pose").offset);
  EXPECT_TRUE(tcp.isApprox(env.tcp_pose().translation(), 1e-12));
  EXPECT_NEAR(o.segment<4>(l.at("tcp_pose").offset + 3).norm(), 1.0, 1e-12);
  EXPECT_TRUE(o.segment<3>(l.at("tcp_to_obj_pos").offset).isApprox(o.segment<3>(l.at("obj_pose").offset) - tcp, 1e-12));
  EXPECT_TRUE(o.segment<3>(l.at("obj_to_goal_pos").offset)
                  .isApprox(o.segment<3>(l.at("goal_pos").offset) - o.segment<3>(l.at("obj_pose").offset), 1e-12));
  EXPECT_EQ(r.elapsed_steps, 1);
  EXPECT_FALSE(r.truncated);
}

TEST(Env, HorizonTruncatesAndSteppingAfterwardsIsANoOp) {
  const auto model = EnvModel::make(TaskId::kPushCube);
  Env env(model);
  env.reset(1);
  for (int i = 0; i < 50; ++i) env.step(Action::Zero());
  EXPECT_TRUE(env.last().truncated);
  EXPECT_TRUE(env.last().episode_over());
  EXPECT_EQ(env.episode().steps, 50);
  const Eigen::VectorXd before = env.last().obs;
  env.step(Action::Zero());
  EXPECT_EQ(env.last().elapsed_steps, 50);
  EXPECT_EQ(env.last().obs, before);
}

TEST(Env, SafetyFlagsEndTheEpisodeAndTheNextResetWorks) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  Env env(model);
  struct Case {
    std::vector<double> action;
    SafetyFlag flag;
    const char* name;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Case> cases = {
      {{0, 0, nan, 0, 0, 0, 1}, SafetyFlag::kNonfiniteAction, "nonfinite_action"},
      {{0, 0, 0, 0, 0, std::numeric_limits<double>::infinity(), 1}, SafetyFlag::kNonfiniteAction, "nonfinite_action"},
      {{0, 0, 0, 0, 0, 0}, SafetyFlag::kBadActionShape, "bad_action_shape"},
      {{0, 0, 0, 0, 0, 0, 1, 0}, SafetyFlag::kBadActionShape, "bad_action_shape"},
      {{1e9, 0, 0, 0, 0, 0, 1}, SafetyFlag::kActionOutOfRange, "action_out_of_range"},
      {{0, 0, 0, 0, 0, 0, -1e9}, SafetyFlag::kActionOutOfRange, "action_out_of_range"},
  };
  for (const Case& c : cases) {
    env.reset(4);
    env.step(Action::Zero());
    const Eigen::VectorXd before = env.last().obs;
    const StepResult& r = env.step(std::span<const double>(c.action));
    EXPECT_EQ(r.safety, c.flag);
    EXPECT_EQ(safety_flag_name(r.safety), c.name);
    EXPECT_TRUE(r.episode_over());
    EXPECT_FALSE(r.success);
    EXPECT_EQ(r.obs, before) << "nothing is simulated for a rejected action";
    EXPECT_TRUE(r.obs.allFinite());
    EXPECT_EQ(env.episode().safety, c.flag);
    EXPECT_FALSE(env.episode().success_at_end);
    EXPECT_EQ(env.episode().steps, 1);
    // the next episode is unaffected
    env.reset(4);
    EXPECT_EQ(env.last().safety, SafetyFlag::kNone);
    EXPECT_EQ(env.step(Action::Zero()).safety, SafetyFlag::kNone);
  }
}

TEST(Env, LargeButFiniteCommandsAreClippedAndCounted) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  Env env(model);
  env.reset(2);
  Action a = Action::Zero();
  a(0) = 50.0;  // within the magnitude bound: clipped to 1 by the controller, and counted
  a(6) = 3.0;
  EXPECT_EQ(env.step(a).safety, SafetyFlag::kNone);
  EXPECT_EQ(env.episode().clipped_steps, 1);
  env.step(Action::Zero());
  EXPECT_EQ(env.episode().clipped_steps, 1);
}

TEST(Env, LeavingTheWorkspaceEndsTheEpisode) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  Env env(model);
  env.reset(3);
  Action up = Action::Zero();
  up(2) = 1.0;
  up(6) = 1.0;
  int steps = 0;
  while (!env.last().episode_over() && steps < 50) {
    env.step(up);
    ++steps;
  }
  EXPECT_EQ(env.last().safety, SafetyFlag::kWorkspaceViolation);
  EXPECT_GT(env.tcp_pose().translation().z(), model->config().workspace.upper.z());
  EXPECT_EQ(safety_flag_name(env.episode().safety), "workspace_violation");
}

TEST(Env, GraspDetectionSeesAHeldCubeAndNotAFreeOne) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  Env env(model);
  const int grasped_at = model->layout().at("is_grasped").offset;
  env.reset(21);
  GraspLiftScript script;
  bool seen_lift = false;
  for (int i = 0; i < 50 && !env.last().episode_over(); ++i) {
    const TaskSnapshot s = env.snapshot();
    const Action a = script.act(s);
    const StepResult& r = env.step(a);
    if (script.phase() == GraspLiftScript::Phase::kApproach) {
      EXPECT_EQ(r.obs(grasped_at), 0.0);  // open hand, no contact
    }
    if (script.phase() == GraspLiftScript::Phase::kHold) {
      seen_lift = true;
      EXPECT_EQ(r.obs(grasped_at), 1.0);
      const auto [fl, fr] = env.finger_forces();
      EXPECT_GT(fl.norm(), 0.5);
      EXPECT_GT(fr.norm(), 0.5);
    }
  }
  EXPECT_TRUE(seen_lift);
  // open the hand: the cube drops, no grasp
  Action open = Action::Zero();
  open(6) = 1.0;
  env.reset(21);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(env.step(open).obs(grasped_at), 0.0);
}

TEST(Env, ModelRejectsARobotWithoutAPandaArm) {
  EnvConfig cfg;
  cfg.names.tcp_link = "panda_link4";
  EXPECT_THROW(EnvModel::make(TaskId::kPickCube, cfg), std::invalid_argument);
}

}  // namespace
}  // namespace actionshift::sim
