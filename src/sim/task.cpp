// task names, observation layouts, success predicates and dense rewards (facts sections 1 and 3.6)
#include "actionshift/sim/task.hpp"

#include "actionshift/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace actionshift::sim {
namespace {

constexpr std::array<TaskId, 5> kAllTasks = {TaskId::kPickCube, TaskId::kPushCube, TaskId::kPullCube,
                                             TaskId::kStackCube, TaskId::kPegInsertionSide};
constexpr double kCubeHalf = 0.02;

double arm_speed(const TaskSnapshot& s) { return s.qvel.head<7>().norm(); }
double max_arm_joint_speed(const TaskSnapshot& s) { return s.qvel.head<7>().cwiseAbs().maxCoeff(); }

TaskEvaluation eval_pick(const TaskSnapshot& s) {
  const Eigen::Vector3d cube = s.obj[0].translation();
  const double to_goal = (s.goal - cube).norm();
  const bool placed = to_goal <= 0.025;
  const bool robot_static = max_arm_joint_speed(s) <= 0.2;
  TaskEvaluation e;
  e.success = placed && robot_static;
  const double g = s.grasped ? 1.0 : 0.0;
  double r = 1.0 - std::tanh(5.0 * (cube - s.tcp.translation()).norm());
  r += g;
  r += g * (1.0 - std::tanh(5.0 * to_goal));
  r += (placed ? 1.0 : 0.0) * (1.0 - std::tanh(5.0 * arm_speed(s)));
  e.reward = (e.success ? 5.0 : r) / 5.0;
  return e;
}

TaskEvaluation eval_push(const TaskSnapshot& s) {
  const Eigen::Vector3d cube = s.obj[0].translation();
  const double xy = (cube.head<2>() - s.goal.head<2>()).norm();
  TaskEvaluation e;
  e.success = xy < 0.1 && cube.z() < kCubeHalf + 0.005;
  const Eigen::Vector3d push_point = cube - Eigen::Vector3d(kCubeHalf + 0.005, 0, 0);
  const double d = (push_point - s.tcp.translation()).norm();
  double r = 1.0 - std::tanh(5.0 * d);
  if (d < 0.01) {
    const double place = 1.0 - std::tanh(5.0 * xy);
    const double z_keep = 1.0 - std::tanh(5.0 * std::abs(cube.z() - kCubeHalf));
    r += place + place * z_keep;
  }
  e.reward = (e.success ? 4.0 : r) / 4.0;
  return e;
}

TaskEvaluation eval_pull(const TaskSnapshot& s) {
  const Eigen::Vector3d cube = s.obj[0].translation();
  const double xy = (cube.head<2>() - s.goal.head<2>()).norm();
  TaskEvaluation e;
  e.success = xy < 0.1;
  const Eigen::Vector3d pull_point = cube + Eigen::Vector3d(kCubeHalf + 2 * 0.005, 0, 0);
  const double d = (pull_point - s.tcp.translation()).norm();
  double r = 1.0 - std::tanh(5.0 * d);
  if (d < 0.01) r += 1.0 - std::tanh(5.0 * xy);
  e.reward = (e.success ? 3.0 : r) / 3.0;
  return e;
}

TaskEvaluation eval_stack(const TaskSnapshot& s) {
  const Eigen::Vector3d a = s.obj[0].translation();
  const Eigen::Vector3d b = s.obj[1].translation();
  const Eigen::Vector3d off = a - b;
  const bool xy_ok = off.head<2>().norm() <= std::sqrt(2.0) * kCubeHalf + 0.005;
  const bool z_ok = std::abs(off.z() - 2 * kCubeHalf) <= 0.005;
  const bool on_top = xy_ok && z_ok;
  const bool a_static = s.obj_linvel[0].norm() <= 1e-2 && s.obj_angvel[0].norm() <= 0.5;
  TaskEvaluation e;
  e.success = on_top && a_static && !s.grasped;
  double r = 2.0 * (1.0 - std::tanh(5.0 * (s.tcp.translation() - a).norm()));
  if (s.grasped) {
    const Eigen::Vector3d goal = b + Eigen::Vector3d(0, 0, 2 * kCubeHalf);
    r = 4.0 + (1.0 - std::tanh(5.0 * (goal - a).norm()));
  }
  if (on_top) {
    const double ungrasp = s.grasped ? (s.qpos(7) + s.qpos(8)) / 0.08 : 1.0;
    const double stat = 1.0 - std::tanh(10.0 * s.obj_linvel[0].norm() + s.obj_angvel[0].norm());
    r = 6.0 + (ungrasp + stat) / 2.0;
  }
  e.reward = (e.success ? 8.0 : r) / 8.0;
  return e;
}

TaskEvaluation eval_peg(const TaskSnapshot& s) {
  const Eigen::Isometry3d& peg = s.obj[0];
  Eigen::Isometry3d hole = s.obj[1];
  hole.translate(s.hole_offset);
  const Eigen::Vector3d head = peg * Eigen::Vector3d(s.peg_half_length, 0, 0);
  const Eigen::Vector3d head_in_hole = hole.inverse() * head;
  TaskEvaluation e;
  e.success = head_in_hole.x() >= -0.015 && std::abs(head_in_hole.y()) <= s.hole_half_width &&
              std::abs(head_in_hole.z()) <= s.hole_half_width;
  // reaching a grasp point 6 cm behind the peg centre, strict grasp, pre-insertion alignment, insertion
  const Eigen::Vector3d grasp_point = peg * Eigen::Vector3d(-0.06, 0, 0);
  double r = 1.0 - std::tanh(4.0 * (s.tcp.translation() - grasp_point).norm());
  const double g = s.grasped_strict ? 1.0 : 0.0;
  r += g;
  const Eigen::Vector3d centre_in_hole = hole.inverse() * peg.translation();
  const double head_yz = head_in_hole.tail<2>().norm();
  const double centre_yz = centre_in_hole.tail<2>().norm();
  const double pre = 3.0 * (1.0 - std::tanh(0.5 * (head_yz + centre_yz) + 4.5 * std::max(head_yz, centre_yz)));
  r += pre * g;
  if (g > 0.0 && head_yz < 0.01 && centre_yz < 0.01) r += 5.0 * (1.0 - std::tanh(5.0 * head_in_hole.norm()));
  e.reward = (e.success ? 10.0 : r) / 10.0;
  return e;
}

}  // namespace

std::string_view task_name(TaskId task) {
  switch (task) {
    case TaskId::kPickCube: return "pick_cube";
    case TaskId::kPushCube: return "push_cube";
    case TaskId::kPullCube: return "pull_cube";
    case TaskId::kStackCube: return "stack_cube";
    case TaskId::kPegInsertionSide: return "peg_insertion_side";
  }
  return "unknown";
}

TaskId parse_task(std::string_view name) {
  for (TaskId t : kAllTasks)
    if (task_name(t) == name) return t;
  throw InputError("", "task",
                   "unknown task '" + std::string(name) +
                       "' (valid: pick_cube, push_cube, pull_cube, stack_cube, peg_insertion_side)");
}

int task_horizon(TaskId task) { return task == TaskId::kPegInsertionSide ? 100 : 50; }

std::span<const TaskId> all_tasks() { return kAllTasks; }

ObservationLayout::ObservationLayout(const std::vector<std::pair<std::string, int>>& fields) {
  for (const auto& [name, width] : fields) {
    fields_.push_back(ObsField{name, size_, width});
    size_ += width;
  }
}

const ObsField* ObservationLayout::find(std::string_view name) const {
  for (const auto& f : fields_)
    if (f.name == name) return &f;
  return nullptr;
}

const ObsField& ObservationLayout::at(std::string_view name) const {
  if (const ObsField* f = find(name)) return *f;
  throw std::out_of_range("observation has no field '" + std::string(name) + "'");
}

std::string ObservationLayout::to_json() const {
  std::string out = "{\"size\":" + std::to_string(size_) + ",\"fields\":[";
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    if (i) out += ',';
    out += "{\"name\":\"" + fields_[i].name + "\",\"offset\":" + std::to_string(fields_[i].offset) +
           ",\"width\":" + std::to_string(fields_[i].width) + "}";
  }
  return out + "]}";
}

const ObservationLayout& observation_layout(TaskId task) {
  static const ObservationLayout pick({{"qpos", 9}, {"qvel", 9}, {"is_grasped", 1}, {"tcp_pose", 7}, {"goal_pos", 3},
                                       {"obj_pose", 7}, {"tcp_to_obj_pos", 3}, {"obj_to_goal_pos", 3}});
  static const ObservationLayout push({{"qpos", 9}, {"qvel", 9}, {"tcp_pose", 7}, {"goal_pos", 3}, {"obj_pose", 7}});
  static const ObservationLayout stack({{"qpos", 9}, {"qvel", 9}, {"tcp_pose", 7}, {"cubeA_pose", 7}, {"cubeB_pose", 7},
                                        {"tcp_to_cubeA_pos", 3}, {"tcp_to_cubeB_pos", 3}, {"cubeA_to_cubeB_pos", 3}});
  static const ObservationLayout peg({{"qpos", 9}, {"qvel", 9}, {"tcp_pose", 7}, {"peg_pose", 7}, {"peg_half_size", 3},
                                      {"box_hole_pose", 7}, {"box_hole_radius", 1}});
  switch (task) {
    case TaskId::kPickCube: return pick;
    case TaskId::kPushCube:
    case TaskId::kPullCube: return push;
    case TaskId::kStackCube: return stack;
    case TaskId::kPegInsertionSide: return peg;
  }
  return pick;
}

TaskEvaluation evaluate_task(TaskId task, const TaskSnapshot& s) {
  switch (task) {
    case TaskId::kPickCube: return eval_pick(s);
    case TaskId::kPushCube: return eval_push(s);
    case TaskId::kPullCube: return eval_pull(s);
    case TaskId::kStackCube: return eval_stack(s);
    case TaskId::kPegInsertionSide: return eval_peg(s);
  }
  return {};
}

bool is_grasping(const Eigen::Vector3d& force_left, const Eigen::Vector3d& force_right,
                 const Eigen::Vector3d& hand_y_axis, double min_force_n, double max_angle_deg) {
  const double cos_max = std::cos(max_angle_deg * 3.14159265358979323846 / 180.0);
  auto ok = [&](const Eigen::Vector3d& f, const Eigen::Vector3d& dir) {
    const double n = f.norm();
    if (!(n >= min_force_n)) return false;
    return f.dot(dir) / (n * dir.norm()) >= cos_max;
  };
  return ok(force_left, hand_y_axis) && ok(force_right, -hand_y_axis);
}

}  // namespace actionshift::sim
