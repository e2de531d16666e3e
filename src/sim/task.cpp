// The five tasks, each described once: spawn distribution, observation layout and composition,
// success and dense reward, scene geometry, default camera and constants, with the ManiSkill source
// of each (docs/sim.md §5). Adding a task: an enumerator in TaskId and a description here.
#include "actionshift/sim/task.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/sim/kinematics.hpp"
#include "actionshift/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace actionshift::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kPickGoalRadius = 0.025;  // PickCube goal_thresh: success radius and the goal sphere drawn
constexpr double kDiscGoalRadius = 0.1;    // Push/PullCube goal_radius: success radius and the goal disc drawn

// ---- shared pieces

Eigen::Quaterniond yaw_quat(double yaw) { return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())); }

TaskObject cube_object(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  TaskObject o;
  o.boxes.push_back({Eigen::Vector3d::Constant(kCubeHalfSize), Eigen::Vector3d::Zero()});
  o.mass = kObjectDensity * 8.0 * kCubeHalfSize * kCubeHalfSize * kCubeHalfSize;
  o.position = p;
  o.orientation = q;
  return o;
}

void write_pose(Eigen::VectorXd& obs, int offset, const Eigen::Isometry3d& t) {
  obs.segment<3>(offset) = t.translation();
  obs.segment<4>(offset + 3) = matrix_to_quat_wxyz(t.linear());
}

Eigen::Isometry3d at(const Eigen::Isometry3d& frame, const Eigen::Vector3d& offset) {
  Eigen::Isometry3d t = frame;
  t.translate(offset);
  return t;
}

SceneShape scene_box(const Eigen::Isometry3d& pose, const Eigen::Vector3d& full, const Eigen::Vector4f& rgba, int object) {
  SceneShape s;
  s.type = CollisionGeometry::Type::kBox;
  s.pose = pose;
  s.size = full;
  s.part = ScenePart::kObject;
  s.object = object;
  s.rgba = rgba;
  return s;
}

void draw_cube(const Eigen::Isometry3d& pose, const Eigen::Vector4f& rgba, int object, Scene& scene) {
  scene.shapes.push_back(scene_box(pose, Eigen::Vector3d::Constant(2.0 * kCubeHalfSize), rgba, object));
}

const Eigen::Vector4f kGoalColor{0.10f, 0.85f, 0.25f, 0.45f};
const Eigen::Vector4f kBoxColor{0.55f, 0.60f, 0.68f, 1.0f};

// ---- success and reward (ManiSkill's evaluate() and compute_dense_reward())

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
  e.success = xy < 0.1 && cube.z() < kCubeHalfSize + 0.005;
  const Eigen::Vector3d push_point = cube - Eigen::Vector3d(kCubeHalfSize + 0.005, 0, 0);
  const double d = (push_point - s.tcp.translation()).norm();
  double r = 1.0 - std::tanh(5.0 * d);
  if (d < 0.01) {
    const double place = 1.0 - std::tanh(5.0 * xy);
    const double z_keep = 1.0 - std::tanh(5.0 * std::abs(cube.z() - kCubeHalfSize));
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
  const Eigen::Vector3d pull_point = cube + Eigen::Vector3d(kCubeHalfSize + 2 * 0.005, 0, 0);
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
  const bool xy_ok = off.head<2>().norm() <= std::sqrt(2.0) * kCubeHalfSize + 0.005;
  const bool z_ok = std::abs(off.z() - 2 * kCubeHalfSize) <= 0.005;
  const bool on_top = xy_ok && z_ok;
  const bool a_static = s.obj_linvel[0].norm() <= 1e-2 && s.obj_angvel[0].norm() <= 0.5;
  TaskEvaluation e;
  e.success = on_top && a_static && !s.grasped;
  double r = 2.0 * (1.0 - std::tanh(5.0 * (s.tcp.translation() - a).norm()));
  if (s.grasped) {
    const Eigen::Vector3d goal = b + Eigen::Vector3d(0, 0, 2 * kCubeHalfSize);
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

// ---- pick_cube (mani_skill/envs/tasks/tabletop/pick_cube.py)

const ObservationLayout& pick_layout() {
  static const ObservationLayout l({{"qpos", 9}, {"qvel", 9}, {"is_grasped", 1}, {"tcp_pose", 7}, {"goal_pos", 3},
                                    {"obj_pose", 7}, {"tcp_to_obj_pos", 3}, {"obj_to_goal_pos", 3}});
  return l;
}

void pick_spawn(Rng& rng, TaskEpisode& e) {
  const double x = rng.uniform(-0.1, 0.1), y = rng.uniform(-0.1, 0.1);
  const double yaw = rng.uniform(0.0, 2 * kPi);
  e.objects.push_back(cube_object(Eigen::Vector3d(x, y, kCubeHalfSize), yaw_quat(yaw)));
  const double gx = rng.uniform(-0.1, 0.1), gy = rng.uniform(-0.1, 0.1);
  e.goal = Eigen::Vector3d(gx, gy, kCubeHalfSize + rng.uniform(0.0, 0.3));
}

void pick_observe(const TaskSnapshot& s, const ObservationLayout& l, Eigen::VectorXd& obs) {
  const Eigen::Vector3d tcp = s.tcp.translation();
  obs(l.at("is_grasped").offset) = s.grasped ? 1.0 : 0.0;
  obs.segment<3>(l.at("goal_pos").offset) = s.goal;
  write_pose(obs, l.at("obj_pose").offset, s.obj[0]);
  obs.segment<3>(l.at("tcp_to_obj_pos").offset) = s.obj[0].translation() - tcp;
  obs.segment<3>(l.at("obj_to_goal_pos").offset) = s.goal - s.obj[0].translation();
}

void pick_draw(const TaskSnapshot& s, Scene& scene) {
  draw_cube(s.obj[0], kCubeColor, 0, scene);
  SceneShape g;
  g.type = CollisionGeometry::Type::kSphere;
  g.pose = Eigen::Isometry3d::Identity();
  g.pose.translation() = s.goal;
  g.size = Eigen::Vector3d(kPickGoalRadius, 0.0, 0.0);
  g.part = ScenePart::kGoal;
  g.rgba = kGoalColor;
  scene.shapes.push_back(g);
}

// ---- push_cube and pull_cube (push_cube.py, pull_cube.py): the goal disc 0.2 m beyond or behind the cube

const ObservationLayout& push_pull_layout() {
  static const ObservationLayout l({{"qpos", 9}, {"qvel", 9}, {"tcp_pose", 7}, {"goal_pos", 3}, {"obj_pose", 7}});
  return l;
}

void push_pull_spawn(Rng& rng, TaskEpisode& e, double dx) {
  const double x = rng.uniform(-0.1, 0.1), y = rng.uniform(-0.1, 0.1);
  e.objects.push_back(cube_object(Eigen::Vector3d(x, y, kCubeHalfSize), Eigen::Quaterniond::Identity()));
  e.goal = Eigen::Vector3d(x + dx, y, 1e-3);
}
void push_spawn(Rng& rng, TaskEpisode& e) { push_pull_spawn(rng, e, 0.2); }
void pull_spawn(Rng& rng, TaskEpisode& e) { push_pull_spawn(rng, e, -0.2); }

void push_pull_observe(const TaskSnapshot& s, const ObservationLayout& l, Eigen::VectorXd& obs) {
  obs.segment<3>(l.at("goal_pos").offset) = s.goal;
  write_pose(obs, l.at("obj_pose").offset, s.obj[0]);
}

void push_pull_draw(const TaskSnapshot& s, Scene& scene) {
  draw_cube(s.obj[0], kCubeColor, 0, scene);
  SceneShape g;
  g.type = CollisionGeometry::Type::kCylinder;
  g.pose = Eigen::Isometry3d::Identity();
  g.pose.translation() = Eigen::Vector3d(s.goal.x(), s.goal.y(), 0.001);
  g.size = Eigen::Vector3d(kDiscGoalRadius, 0.002, 0.0);
  g.part = ScenePart::kGoal;
  g.rgba = kGoalColor;
  scene.shapes.push_back(g);
}

// ---- stack_cube (stack_cube.py)

const ObservationLayout& stack_layout() {
  static const ObservationLayout l({{"qpos", 9}, {"qvel", 9}, {"tcp_pose", 7}, {"cubeA_pose", 7}, {"cubeB_pose", 7},
                                    {"tcp_to_cubeA_pos", 3}, {"tcp_to_cubeB_pos", 3}, {"cubeA_to_cubeB_pos", 3}});
  return l;
}

void stack_spawn(Rng& rng, TaskEpisode& e) {
  const double ox = rng.uniform(-0.1, 0.1), oy = rng.uniform(-0.1, 0.1);
  const double ax = rng.uniform(-0.1, 0.1), ay = rng.uniform(-0.2, 0.2);
  const double min_sep = 2.0 * (std::sqrt(2.0) * kCubeHalfSize + 0.001);
  double bx = 0.0, by = 0.0;
  bool placed = false;
  for (int tries = 0; tries < 100 && !placed; ++tries) {
    bx = rng.uniform(-0.1, 0.1);
    by = rng.uniform(-0.2, 0.2);
    placed = std::hypot(bx - ax, by - ay) > min_sep;
  }
  if (!placed) bx = by = 0.0;  // ManiSkill's sampler quirk
  const double yaw_a = rng.uniform(0.0, 2 * kPi), yaw_b = rng.uniform(0.0, 2 * kPi);
  e.objects.push_back(cube_object(Eigen::Vector3d(ox + ax, oy + ay, kCubeHalfSize), yaw_quat(yaw_a)));
  e.objects.push_back(cube_object(Eigen::Vector3d(ox + bx, oy + by, kCubeHalfSize), yaw_quat(yaw_b)));
}

void stack_observe(const TaskSnapshot& s, const ObservationLayout& l, Eigen::VectorXd& obs) {
  const Eigen::Vector3d tcp = s.tcp.translation();
  write_pose(obs, l.at("cubeA_pose").offset, s.obj[0]);
  write_pose(obs, l.at("cubeB_pose").offset, s.obj[1]);
  obs.segment<3>(l.at("tcp_to_cubeA_pos").offset) = s.obj[0].translation() - tcp;
  obs.segment<3>(l.at("tcp_to_cubeB_pos").offset) = s.obj[1].translation() - tcp;
  obs.segment<3>(l.at("cubeA_to_cubeB_pos").offset) = s.obj[1].translation() - s.obj[0].translation();
}

void stack_draw(const TaskSnapshot& s, Scene& scene) {
  draw_cube(s.obj[0], kCubeColor, 0, scene);
  draw_cube(s.obj[1], kCubeBColor, 1, scene);
}

// ---- peg_insertion_side (peg_insertion_side.py)

const ObservationLayout& peg_layout() {
  static const ObservationLayout l({{"qpos", 9}, {"qvel", 9}, {"tcp_pose", 7}, {"peg_pose", 7}, {"peg_half_size", 3},
                                    {"box_hole_pose", 7}, {"box_hole_radius", 1}});
  return l;
}

void peg_spawn(Rng& rng, TaskEpisode& e) {
  const double L = rng.uniform(0.085, 0.125);
  const double r = rng.uniform(0.015, 0.025);
  const double cy = 0.5 * (L - r) * rng.uniform(-1.0, 1.0);
  const double cz = 0.5 * (L - r) * rng.uniform(-1.0, 1.0);
  e.peg_half_length = L;
  e.peg_half_width = r;
  e.hole_half_width = r + kPegHoleClearance;
  e.hole_offset = Eigen::Vector3d(0.0, cy, cz);
  const double px = rng.uniform(-0.1, 0.1), py = rng.uniform(-0.3, 0.0);
  const double pyaw = rng.uniform(kPi / 2 - kPi / 3, kPi / 2 + kPi / 3);
  const double bx = rng.uniform(-0.05, 0.05), by = rng.uniform(0.2, 0.4);
  const double byaw = rng.uniform(kPi / 2 - kPi / 8, kPi / 2 + kPi / 8);
  TaskObject peg;
  peg.boxes.push_back({Eigen::Vector3d(L, r, r), Eigen::Vector3d::Zero()});
  peg.mass = kObjectDensity * 8.0 * L * r * r;
  peg.position = Eigen::Vector3d(px, py, r);
  peg.orientation = yaw_quat(pyaw);
  e.objects.push_back(peg);
  TaskObject box;
  for (const TaskBox& part : box_with_hole(L, e.hole_half_width, e.hole_offset)) box.boxes.push_back(part);
  box.mass = 0.0;
  box.position = Eigen::Vector3d(bx, by, L);
  box.orientation = yaw_quat(byaw);
  e.objects.push_back(box);
}

void peg_observe(const TaskSnapshot& s, const ObservationLayout& l, Eigen::VectorXd& obs) {
  write_pose(obs, l.at("peg_pose").offset, s.obj[0]);
  obs.segment<3>(l.at("peg_half_size").offset) = Eigen::Vector3d(s.peg_half_length, s.peg_half_width, s.peg_half_width);
  Eigen::Isometry3d hole = s.obj[1];
  hole.translate(s.hole_offset);
  write_pose(obs, l.at("box_hole_pose").offset, hole);
  obs(l.at("box_hole_radius").offset) = s.hole_half_width;
}

void peg_draw(const TaskSnapshot& s, Scene& scene) {
  const double L = s.peg_half_length, r = s.peg_half_width;
  // the peg's collision box (L, r, r) drawn as two halves: head (+x, inserted first) and tail
  scene.shapes.push_back(scene_box(at(s.obj[0], {0.5 * L, 0, 0}), Eigen::Vector3d(L, 2 * r, 2 * r), kCubeColor, 0));
  scene.shapes.push_back(scene_box(at(s.obj[0], {-0.5 * L, 0, 0}), Eigen::Vector3d(L, 2 * r, 2 * r), kPegTailColor, 0));
  for (const TaskBox& part : box_with_hole(L, s.hole_half_width, s.hole_offset))
    scene.shapes.push_back(scene_box(at(s.obj[1], part.offset), 2.0 * part.half_extents, kBoxColor, 1));
}

// ---- the descriptions, in TaskId order

constexpr std::size_t kTaskCount = 5;

const std::array<TaskDescription, kTaskCount>& descriptions() {
  static const std::array<TaskDescription, kTaskCount> d{{
      {TaskId::kPickCube, "pick_cube", "PickCube-v1", "mani_skill/envs/tasks/tabletop/pick_cube.py", 50, kPi / 4, 0.5,
       &pick_layout, {"obj_pose", "", "goal_pos", "is_grasped"}, std::nullopt, &pick_spawn, &pick_observe, &eval_pick,
       &pick_draw},
      {TaskId::kPushCube, "push_cube", "PushCube-v1", "mani_skill/envs/tasks/tabletop/push_cube.py", 50, kPi / 4, 0.5,
       &push_pull_layout, {"obj_pose", "", "goal_pos", ""}, std::nullopt, &push_spawn, &push_pull_observe, &eval_push,
       &push_pull_draw},
      {TaskId::kPullCube, "pull_cube", "PullCube-v1", "mani_skill/envs/tasks/tabletop/pull_cube.py", 50, kPi / 4, 0.5,
       &push_pull_layout, {"obj_pose", "", "goal_pos", ""}, std::nullopt, &pull_spawn, &push_pull_observe, &eval_pull,
       &push_pull_draw},
      // panda_wristcam keyframe (joint 7 = -pi/4)
      {TaskId::kStackCube, "stack_cube", "StackCube-v1", "mani_skill/envs/tasks/tabletop/stack_cube.py", 50, -kPi / 4, 0.5,
       &stack_layout, {"cubeA_pose", "cubeB_pose", "", ""}, std::nullopt, &stack_spawn, &stack_observe, &eval_stack,
       &stack_draw},
      // panda_wristcam keyframe; a longer horizon; ManiSkill's own human-render camera for this task
      {TaskId::kPegInsertionSide, "peg_insertion_side", "PegInsertionSide-v1",
       "mani_skill/envs/tasks/tabletop/peg_insertion_side.py", 100, -kPi / 4, 0.2, &peg_layout,
       {"peg_pose", "box_hole_pose", "", ""},
       TaskCamera{Eigen::Vector3d(0.5, -0.5, 0.8), Eigen::Vector3d(0.05, -0.1, 0.4)}, &peg_spawn, &peg_observe,
       &eval_peg, &peg_draw},
  }};
  return d;
}

}  // namespace

const TaskDescription& task_description(TaskId task) {
  const auto& d = descriptions();
  const auto i = static_cast<std::size_t>(task);
  if (i >= d.size() || d[i].id != task) throw std::invalid_argument("unknown task id " + std::to_string(static_cast<int>(task)));
  return d[i];
}

std::array<TaskBox, 4> box_with_hole(double peg_half_length, double hole_half_width, const Eigen::Vector3d& hole_offset) {
  const double L = peg_half_length;
  const double inner = hole_half_width, outer = L, depth = L;
  const double thick = 0.5 * (outer - inner);
  const double h0 = 0.5 * hole_offset.y(), h1 = 0.5 * hole_offset.z();
  const double off = thick + inner;
  auto part = [](double hx, double hy, double hz, double x, double y, double z) {
    return TaskBox{Eigen::Vector3d(hx, hy, hz), Eigen::Vector3d(x, y, z)};
  };
  return {part(depth, thick - h0, outer, 0, off + h0, 0), part(depth, thick + h0, outer, 0, -off + h0, 0),
          part(depth, outer, thick - h1, 0, 0, off + h1), part(depth, outer, thick + h1, 0, 0, -off + h1)};
}

std::string_view task_name(TaskId task) { return task_description(task).name; }

TaskId parse_task(std::string_view name) {
  std::string valid;
  for (const TaskDescription& d : descriptions()) {
    if (d.name == name) return d.id;
    valid += (valid.empty() ? "" : ", ") + std::string(d.name);
  }
  throw InputError("", "task", "unknown task '" + std::string(name) + "' (valid: " + valid + ")");
}

int task_horizon(TaskId task) { return task_description(task).horizon; }

std::span<const TaskId> all_tasks() {
  static const std::array<TaskId, kTaskCount> ids = [] {
    std::array<TaskId, kTaskCount> a{};
    for (std::size_t i = 0; i < kTaskCount; ++i) a[i] = descriptions()[i].id;
    return a;
  }();
  return ids;
}

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

const ObservationLayout& observation_layout(TaskId task) { return task_description(task).layout(); }

TaskEvaluation evaluate_task(TaskId task, const TaskSnapshot& s) { return task_description(task).evaluate(s); }

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
