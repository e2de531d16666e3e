// success predicates and dense rewards on constructed states; grasp predicate; layouts
#include "actionshift/sim/task.hpp"

#include "actionshift/core/error.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace actionshift::sim {
namespace {

Eigen::Isometry3d at(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

TEST(Tasks, NamesHorizonsAndLayoutSizes) {
  EXPECT_EQ(parse_task("pick_cube"), TaskId::kPickCube);
  EXPECT_EQ(parse_task("peg_insertion_side"), TaskId::kPegInsertionSide);
  EXPECT_THROW(parse_task("PickCube-v1"), InputError);
  for (TaskId t : all_tasks()) EXPECT_EQ(parse_task(task_name(t)), t);
  EXPECT_EQ(task_horizon(TaskId::kStackCube), 50);
  EXPECT_EQ(task_horizon(TaskId::kPegInsertionSide), 100);
  EXPECT_EQ(observation_layout(TaskId::kPickCube).size(), 42);
  EXPECT_EQ(observation_layout(TaskId::kPushCube).size(), 35);
  EXPECT_EQ(observation_layout(TaskId::kPullCube).size(), 35);
  EXPECT_EQ(observation_layout(TaskId::kStackCube).size(), 48);
  EXPECT_EQ(observation_layout(TaskId::kPegInsertionSide).size(), 43);
  const auto& pick = observation_layout(TaskId::kPickCube);
  EXPECT_EQ(pick.at("is_grasped").offset, 18);
  EXPECT_EQ(pick.at("tcp_pose").offset, 19);
  EXPECT_EQ(pick.at("tcp_pose").width, 7);
  EXPECT_EQ(pick.at("obj_to_goal_pos").offset, 39);
  EXPECT_EQ(observation_layout(TaskId::kPushCube).at("tcp_pose").offset, 18);
  EXPECT_EQ(pick.find("cubeA_pose"), nullptr);
  EXPECT_EQ(observation_layout(TaskId::kStackCube).to_json().rfind("{\"size\":48,\"fields\":[{\"name\":\"qpos\",\"offset\":0,\"width\":9}", 0), 0u);
}

TEST(Tasks, PickCubeNeedsPlacedAndStaticNotGrasped) {
  TaskSnapshot s;
  s.goal = Eigen::Vector3d(0.05, 0.0, 0.2);
  s.obj[0] = at(0.05, 0.0, 0.18);
  EXPECT_TRUE(evaluate_task(TaskId::kPickCube, s).success);  // 2 cm from goal, robot still
  EXPECT_DOUBLE_EQ(evaluate_task(TaskId::kPickCube, s).reward, 1.0);
  s.qvel(3) = 0.25;
  EXPECT_FALSE(evaluate_task(TaskId::kPickCube, s).success);  // moving arm
  s.qvel(3) = 0.0;
  s.qvel(7) = 5.0;  // finger speed does not count
  EXPECT_TRUE(evaluate_task(TaskId::kPickCube, s).success);
  s.obj[0] = at(0.05, 0.0, 0.174);
  EXPECT_FALSE(evaluate_task(TaskId::kPickCube, s).success);  // 2.6 cm
  const double r0 = evaluate_task(TaskId::kPickCube, s).reward;
  s.grasped = true;
  EXPECT_GT(evaluate_task(TaskId::kPickCube, s).reward, r0);
}

TEST(Tasks, PushCubeNeedsTheDiscAndTheTable) {
  TaskSnapshot s;
  s.goal = Eigen::Vector3d(0.2, 0.0, 0.001);
  s.obj[0] = at(0.11, 0.0, 0.02);
  EXPECT_TRUE(evaluate_task(TaskId::kPushCube, s).success);
  s.obj[0] = at(0.09, 0.0, 0.02);
  EXPECT_FALSE(evaluate_task(TaskId::kPushCube, s).success);
  s.obj[0] = at(0.2, 0.0, 0.03);  // lifted over the disc
  EXPECT_FALSE(evaluate_task(TaskId::kPushCube, s).success);
}

TEST(Tasks, PullCubeNeedsOnlyTheDisc) {
  TaskSnapshot s;
  s.goal = Eigen::Vector3d(-0.2, 0.05, 0.001);
  s.obj[0] = at(-0.25, 0.1, 0.02);
  EXPECT_TRUE(evaluate_task(TaskId::kPullCube, s).success);
  s.obj[0] = at(-0.2, 0.05, 0.1);
  EXPECT_TRUE(evaluate_task(TaskId::kPullCube, s).success);  // no height check
  s.obj[0] = at(-0.05, 0.05, 0.02);
  EXPECT_FALSE(evaluate_task(TaskId::kPullCube, s).success);
}

TEST(Tasks, StackCubeNeedsOnTopStaticAndReleased) {
  TaskSnapshot s;
  s.obj[1] = at(0.0, 0.0, 0.02, 0.3);
  s.obj[0] = at(0.02, 0.02, 0.062, 1.0);
  EXPECT_TRUE(evaluate_task(TaskId::kStackCube, s).success);
  s.grasped = true;
  EXPECT_FALSE(evaluate_task(TaskId::kStackCube, s).success);
  s.grasped = false;
  s.obj_linvel[0] = Eigen::Vector3d(0.02, 0, 0);
  EXPECT_FALSE(evaluate_task(TaskId::kStackCube, s).success);
  s.obj_linvel[0].setZero();
  s.obj[0] = at(0.025, 0.025, 0.06);  // xy offset 3.5 cm > 3.33 cm
  EXPECT_FALSE(evaluate_task(TaskId::kStackCube, s).success);
  s.obj[0] = at(0.0, 0.0, 0.067);  // 7 mm too high
  EXPECT_FALSE(evaluate_task(TaskId::kStackCube, s).success);
}

TEST(Tasks, PegInsertionNeedsTheHeadInsideTheHole) {
  TaskSnapshot s;
  s.peg_half_length = 0.1;
  s.peg_half_width = 0.02;
  s.hole_half_width = 0.023;
  s.hole_offset = Eigen::Vector3d(0, 0.01, -0.02);
  const double yaw = std::numbers::pi / 2;  // box x (hole axis) along world y
  s.obj[1] = at(0.0, 0.3, 0.1, yaw);
  const Eigen::Vector3d hole = s.obj[1] * s.hole_offset;
  // peg along the hole axis with its head 1 cm short of the box centre plane: inside (x >= -0.015)
  s.obj[0] = at(hole.x(), hole.y() - 0.01 - 0.1, hole.z(), yaw);
  EXPECT_TRUE(evaluate_task(TaskId::kPegInsertionSide, s).success);
  s.obj[0] = at(hole.x(), hole.y() - 0.02 - 0.1, hole.z(), yaw);  // head 2 cm short
  EXPECT_FALSE(evaluate_task(TaskId::kPegInsertionSide, s).success);
  s.obj[0] = at(hole.x(), hole.y() - 0.1, hole.z() + 0.025, yaw);  // off the hole in z
  EXPECT_FALSE(evaluate_task(TaskId::kPegInsertionSide, s).success);
}

TEST(Tasks, GraspPredicateNeedsBothFingersPushedOutward) {
  const Eigen::Vector3d y(0, -1, 0);  // hand y at rest is world -y
  EXPECT_TRUE(is_grasping(Eigen::Vector3d(0, -3, 0), Eigen::Vector3d(0, 3, 0), y));
  EXPECT_FALSE(is_grasping(Eigen::Vector3d(0, -0.4, 0), Eigen::Vector3d(0, 3, 0), y));  // below 0.5 N
  EXPECT_FALSE(is_grasping(Eigen::Vector3d(0, 3, 0), Eigen::Vector3d(0, -3, 0), y));    // pulled inward
  EXPECT_FALSE(is_grasping(Eigen::Vector3d(0, -3, 0), Eigen::Vector3d::Zero(), y));    // one finger only
  // 80 deg off the opening direction passes at 85, fails at 20
  const Eigen::Vector3d tilted = 3.0 * (std::cos(80 * std::numbers::pi / 180) * y + std::sin(80 * std::numbers::pi / 180) * Eigen::Vector3d::UnitZ());
  EXPECT_TRUE(is_grasping(tilted, Eigen::Vector3d(0, 3, 0), y));
  EXPECT_FALSE(is_grasping(tilted, Eigen::Vector3d(0, 3, 0), y, 0.5, 20.0));
}


// every task's description is complete and consistent: the one place a task is defined
TEST(TaskDescription, EveryTaskIsDescribedCompletely) {
  for (const TaskId t : all_tasks()) {
    const TaskDescription& d = task_description(t);
    EXPECT_EQ(d.id, t);
    EXPECT_EQ(parse_task(d.name), t);
    EXPECT_EQ(task_name(t), d.name);
    EXPECT_TRUE(d.maniskill_id.ends_with("-v1")) << d.name;
    EXPECT_TRUE(d.maniskill_source.starts_with("mani_skill/envs/tasks/")) << d.name;
    EXPECT_GT(d.horizon, 0);
    EXPECT_EQ(task_horizon(t), d.horizon);
    EXPECT_EQ(std::abs(d.rest_wrist), std::numbers::pi / 4);
    EXPECT_GT(d.gate0_floor, 0.0);
    ASSERT_TRUE(d.layout && d.spawn && d.observe && d.evaluate && d.draw) << d.name;
    EXPECT_EQ(&observation_layout(t), &d.layout());
    for (const char* common : {"qpos", "qvel", "tcp_pose"}) EXPECT_NE(d.layout().find(common), nullptr) << d.name << " " << common;
    for (std::string_view role : {d.roles.object, d.roles.object_b, d.roles.goal, d.roles.grasped}) {
      if (!role.empty()) {
        EXPECT_NE(d.layout().find(role), nullptr) << d.name << " " << role;
      }
    }
    EXPECT_FALSE(d.roles.object.empty()) << d.name;
  }
}

TEST(TaskDescription, BoxWithHoleLeavesTheHoleOpen) {
  // four walls around a square hole of half width w centred at (cy, cz): no wall reaches into it
  const double L = 0.1, w = 0.023;
  const Eigen::Vector3d hole(0.0, 0.01, -0.015);
  for (const TaskBox& b : box_with_hole(L, w, hole)) {
    EXPECT_GT(b.half_extents.minCoeff(), 0.0);
    const Eigen::Vector3d lo = b.offset - b.half_extents, hi = b.offset + b.half_extents;
    const bool clear_y = hi.y() <= hole.y() - w + 1e-12 || lo.y() >= hole.y() + w - 1e-12;
    const bool clear_z = hi.z() <= hole.z() - w + 1e-12 || lo.z() >= hole.z() + w - 1e-12;
    EXPECT_TRUE(clear_y || clear_z) << b.offset.transpose();
  }
}

}  // namespace
}  // namespace actionshift::sim
