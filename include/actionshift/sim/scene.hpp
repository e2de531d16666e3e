#pragma once
/// \file
/// A read-only snapshot of everything visible in an environment, for renderers: every collision
/// shape of the robot at its world pose, the table, the task objects (cubes, peg, box with a hole)
/// and the goal marker, each with a display colour. Built from public Env / EnvModel accessors only;
/// it never changes the environment.

#include "actionshift/sim/env.hpp"
#include "actionshift/sim/robot_description.hpp"
#include "actionshift/sim/task.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <vector>

namespace actionshift::sim {

/// What a shape belongs to.
enum class ScenePart {
  kRobot,   ///< a collision shape of a robot link
  kTable,   ///< the table top box (top surface at z = 0)
  kGround,  ///< the floor under the table
  kObject,  ///< a task object (cube, cube A/B, peg, box with a hole)
  kGoal,    ///< a goal marker (not simulated: PickCube's goal sphere, Push/Pull's goal disc)
};

/// One drawable shape, world frame.
struct SceneShape {
  CollisionGeometry::Type type{CollisionGeometry::Type::kBox};
  Eigen::Isometry3d pose{Eigen::Isometry3d::Identity()};  ///< shape frame in the world
  /// As CollisionGeometry: box full extents [m]; sphere (r, 0, 0); cylinder (r, length, 0) along z.
  Eigen::Vector3d size{Eigen::Vector3d::Zero()};
  std::shared_ptr<const MeshData> mesh;  ///< kMesh only (vertices; draw their convex hull)
  ScenePart part{ScenePart::kRobot};
  int object{-1};                        ///< kObject: index of the task object (0 = cube / cube A / peg)
  Eigen::Vector4f rgba{1.0f, 1.0f, 1.0f, 1.0f};  ///< display colour, linear [0, 1]
};

/// Everything visible at one instant.
struct Scene {
  TaskId task{TaskId::kPickCube};
  std::vector<SceneShape> shapes;
};

/// Display colours (ManiSkill's: red cube / cube A, green cube B, a two-tone peg).
inline const Eigen::Vector4f kCubeColor{0.85f, 0.08f, 0.08f, 1.0f};   ///< cube (pick, push, pull), cube A, peg head
inline const Eigen::Vector4f kCubeBColor{0.10f, 0.70f, 0.15f, 1.0f};  ///< stack_cube's cube B
inline const Eigen::Vector4f kPegTailColor{0.15f, 0.25f, 0.85f, 1.0f};  ///< second half of the peg

/// Half side of the task cubes [m]: sim::kCubeHalfSize (task.hpp), under the name renderers used first.
inline constexpr double kSceneCubeHalf = kCubeHalfSize;

/// The scene of an environment (call it after reset(): before, the objects are not yet placed).
Scene scene_of(const Env& env);

}  // namespace actionshift::sim
