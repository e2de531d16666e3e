// scene snapshot for renderers: robot collision shapes at their world poses, table, objects, goal.
// Read-only: everything comes from Env::snapshot(), Env::qpos() and the EnvModel's robot description.
#include "actionshift/sim/scene.hpp"

#include <stdexcept>

namespace actionshift::sim {

namespace {

using Type = CollisionGeometry::Type;

// the table of ManiSkill's TableSceneBuilder (the same box the physics world collides with)
constexpr double kTableHalfX = 0.6045, kTableHalfY = 1.209, kTableHalfZ = 0.45982, kTableCenterX = -0.12;
constexpr double kTableHeight = 0.9196429;
constexpr double kPickGoalRadius = 0.025;  // PickCube goal_thresh: the goal sphere's radius
constexpr double kDiscGoalRadius = 0.1;    // Push/PullCube goal_radius

const Eigen::Vector4f kRobotColor{0.92f, 0.92f, 0.90f, 1.0f};
const Eigen::Vector4f kRobotDarkColor{0.25f, 0.25f, 0.27f, 1.0f};  // hand and fingers
const Eigen::Vector4f kTableColor{0.62f, 0.48f, 0.33f, 1.0f};
const Eigen::Vector4f kGroundColor{0.55f, 0.57f, 0.60f, 1.0f};
const Eigen::Vector4f kGoalColor{0.10f, 0.85f, 0.25f, 0.45f};
const Eigen::Vector4f kBoxColor{0.55f, 0.60f, 0.68f, 1.0f};

Eigen::Isometry3d at(const Eigen::Isometry3d& frame, const Eigen::Vector3d& offset) {
  Eigen::Isometry3d t = frame;
  t.translate(offset);
  return t;
}

SceneShape box(const Eigen::Isometry3d& pose, const Eigen::Vector3d& full, ScenePart part, const Eigen::Vector4f& rgba,
               int object = -1) {
  SceneShape s;
  s.type = Type::kBox;
  s.pose = pose;
  s.size = full;
  s.part = part;
  s.object = object;
  s.rgba = rgba;
  return s;
}

bool dark_link(const std::string& name) {
  return name.find("hand") != std::string::npos || name.find("finger") != std::string::npos ||
         name.find("leftfinger") != std::string::npos || name.find("rightfinger") != std::string::npos;
}

void add_robot(const Env& env, Scene& scene) {
  const EnvModel& m = env.model();
  const RobotDescription& robot = m.robot();
  const Eigen::Matrix<double, 9, 1> q9 = env.qpos();
  std::vector<double> q(robot.joints.size(), 0.0);
  const auto& arm = m.arm().joint_indices();
  for (std::size_t i = 0; i < arm.size() && i < 7; ++i) q[static_cast<std::size_t>(arm[i])] = q9(static_cast<int>(i));
  q[static_cast<std::size_t>(robot.joint_index(m.config().names.left_finger_joint))] = q9(7);
  q[static_cast<std::size_t>(robot.joint_index(m.config().names.right_finger_joint))] = q9(8);
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = m.config().robot_base;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const LinkDescription& link = robot.links[l];
    if (link.collisions.empty()) continue;
    const Eigen::Isometry3d link_world = base * robot.link_pose(static_cast<int>(l), q);
    for (const CollisionGeometry& g : link.collisions) {
      SceneShape s;
      s.type = g.type;
      s.pose = link_world * g.origin;
      s.size = g.size;
      s.mesh = g.mesh;
      s.part = ScenePart::kRobot;
      s.rgba = dark_link(link.name) ? kRobotDarkColor : kRobotColor;
      scene.shapes.push_back(std::move(s));
    }
  }
}

// PegInsertionSide's box with a hole along its x axis: the four static parts of ManiSkill's
// _build_box_with_hole, from the episode's peg and hole sizes (the same formula as the environment)
void add_box_with_hole(const TaskSnapshot& s, Scene& scene) {
  const double L = s.peg_half_length;
  const double inner = s.hole_half_width, outer = L, depth = L;
  const double thick = 0.5 * (outer - inner);
  const double h0 = 0.5 * s.hole_offset.y(), h1 = 0.5 * s.hole_offset.z();
  const double off = thick + inner;
  auto part = [&](double hx, double hy, double hz, double x, double y, double z) {
    scene.shapes.push_back(box(at(s.obj[1], {x, y, z}), 2.0 * Eigen::Vector3d(hx, hy, hz), ScenePart::kObject, kBoxColor, 1));
  };
  part(depth, thick - h0, outer, 0, off + h0, 0);
  part(depth, thick + h0, outer, 0, -off + h0, 0);
  part(depth, outer, thick - h1, 0, 0, off + h1);
  part(depth, outer, thick + h1, 0, 0, -off + h1);
}

}  // namespace

Scene scene_of(const Env& env) {
  Scene scene;
  scene.task = env.model().task();
  const TaskSnapshot s = env.snapshot();

  // floor and table
  Eigen::Isometry3d ground = Eigen::Isometry3d::Identity();
  ground.translation() = Eigen::Vector3d(kTableCenterX, 0.0, -kTableHeight - 0.005);
  scene.shapes.push_back(box(ground, Eigen::Vector3d(8.0, 8.0, 0.01), ScenePart::kGround, kGroundColor));
  Eigen::Isometry3d table = Eigen::Isometry3d::Identity();
  table.translation() = Eigen::Vector3d(kTableCenterX, 0.0, -kTableHalfZ);
  scene.shapes.push_back(box(table, 2.0 * Eigen::Vector3d(kTableHalfX, kTableHalfY, kTableHalfZ), ScenePart::kTable, kTableColor));

  add_robot(env, scene);

  const Eigen::Vector3d cube_full = Eigen::Vector3d::Constant(2.0 * kSceneCubeHalf);
  switch (scene.task) {
    case TaskId::kPickCube: {
      scene.shapes.push_back(box(s.obj[0], cube_full, ScenePart::kObject, kCubeColor, 0));
      SceneShape g;
      g.type = Type::kSphere;
      g.pose = Eigen::Isometry3d::Identity();
      g.pose.translation() = s.goal;
      g.size = Eigen::Vector3d(kPickGoalRadius, 0.0, 0.0);
      g.part = ScenePart::kGoal;
      g.rgba = kGoalColor;
      scene.shapes.push_back(g);
      break;
    }
    case TaskId::kPushCube:
    case TaskId::kPullCube: {
      scene.shapes.push_back(box(s.obj[0], cube_full, ScenePart::kObject, kCubeColor, 0));
      SceneShape g;
      g.type = Type::kCylinder;
      g.pose = Eigen::Isometry3d::Identity();
      g.pose.translation() = Eigen::Vector3d(s.goal.x(), s.goal.y(), 0.001);
      g.size = Eigen::Vector3d(kDiscGoalRadius, 0.002, 0.0);
      g.part = ScenePart::kGoal;
      g.rgba = kGoalColor;
      scene.shapes.push_back(g);
      break;
    }
    case TaskId::kStackCube:
      scene.shapes.push_back(box(s.obj[0], cube_full, ScenePart::kObject, kCubeColor, 0));
      scene.shapes.push_back(box(s.obj[1], cube_full, ScenePart::kObject, kCubeBColor, 1));
      break;
    case TaskId::kPegInsertionSide: {
      const double L = s.peg_half_length, r = s.peg_half_width;
      // the peg's collision box (L, r, r) drawn as two halves: head (+x, inserted first) and tail
      scene.shapes.push_back(box(at(s.obj[0], {0.5 * L, 0, 0}), Eigen::Vector3d(L, 2 * r, 2 * r), ScenePart::kObject, kCubeColor, 0));
      scene.shapes.push_back(box(at(s.obj[0], {-0.5 * L, 0, 0}), Eigen::Vector3d(L, 2 * r, 2 * r), ScenePart::kObject, kPegTailColor, 0));
      add_box_with_hole(s, scene);
      break;
    }
  }
  return scene;
}

}  // namespace actionshift::sim
