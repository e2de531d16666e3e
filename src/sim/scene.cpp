// scene snapshot for renderers: robot collision shapes at their world poses, table, objects, goal.
// Read-only: everything comes from Env::snapshot(), Env::qpos() and the EnvModel's robot description.
#include "actionshift/sim/scene.hpp"

#include <stdexcept>

namespace actionshift::sim {

namespace {

using Type = CollisionGeometry::Type;

const Eigen::Vector4f kRobotColor{0.92f, 0.92f, 0.90f, 1.0f};
const Eigen::Vector4f kRobotDarkColor{0.25f, 0.25f, 0.27f, 1.0f};  // hand and fingers
const Eigen::Vector4f kTableColor{0.62f, 0.48f, 0.33f, 1.0f};
const Eigen::Vector4f kGroundColor{0.55f, 0.57f, 0.60f, 1.0f};

SceneShape box(const Eigen::Isometry3d& pose, const Eigen::Vector3d& full, ScenePart part, const Eigen::Vector4f& rgba) {
  SceneShape s;
  s.type = Type::kBox;
  s.pose = pose;
  s.size = full;
  s.part = part;
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

}  // namespace

Scene scene_of(const Env& env) {
  Scene scene;
  scene.task = env.model().task();
  const TaskSnapshot s = env.snapshot();

  // floor and table
  Eigen::Isometry3d ground = Eigen::Isometry3d::Identity();
  ground.translation() = Eigen::Vector3d(kTable.center_x, 0.0, -kTable.height - 0.005);
  scene.shapes.push_back(box(ground, Eigen::Vector3d(8.0, 8.0, 0.01), ScenePart::kGround, kGroundColor));
  Eigen::Isometry3d table = Eigen::Isometry3d::Identity();
  table.translation() = Eigen::Vector3d(kTable.center_x, 0.0, -kTable.half_z);
  scene.shapes.push_back(box(table, 2.0 * Eigen::Vector3d(kTable.half_x, kTable.half_y, kTable.half_z), ScenePart::kTable, kTableColor));

  add_robot(env, scene);

  task_description(scene.task).draw(s, scene);  // the task's objects and goal marker
  return scene;
}

}  // namespace actionshift::sim
