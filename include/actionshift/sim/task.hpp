#pragma once
/// \file
/// The five ManiSkill3 table-top tasks, each described once (TaskDescription: name, ManiSkill source,
/// horizon, rest keyframe, spawn distribution, observation layout, success and reward, scene geometry,
/// camera, competence floor). The simulator, the policies, the renderer and the Python module read
/// the description; nothing else knows a task (docs/sim.md §5, "What a task defines").

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift {
class Rng;
}

namespace actionshift::sim {

struct Scene;

enum class TaskId {
  kPickCube,          ///< "pick_cube": lift the cube to a goal point (horizon 50)
  kPushCube,          ///< "push_cube": push the cube onto a goal disc 0.2 m further in +x (horizon 50)
  kPullCube,          ///< "pull_cube": pull the cube onto a goal disc 0.2 m back in -x (horizon 50)
  kStackCube,         ///< "stack_cube": put cube A on cube B and let go (horizon 50)
  kPegInsertionSide,  ///< "peg_insertion_side": insert the peg sideways into the box hole (horizon 100)
};

/// ManiSkill's table (TableSceneBuilder, mani_skill/utils/scene_builder/table/scene_builder.py): a box
/// of these half extents whose top face is the plane z = 0, centred at x = -0.12; the floor lies
/// kTableHeight below the top.
struct TableGeometry {
  double half_x{0.6045}, half_y{1.209}, half_z{0.45982};  ///< [m] half extents of the collision box
  double center_x{-0.12};                                 ///< [m] box centre x (y = 0, z = -half_z)
  double height{0.9196429};                               ///< [m] table top above the floor
};
inline constexpr TableGeometry kTable{};

/// Half side of every task cube [m] (ManiSkill's PickCube/PushCube/PullCube/StackCube `cube_half_size`).
inline constexpr double kCubeHalfSize = 0.02;
/// Density of every task object [kg/m^3] (SAPIEN's default).
inline constexpr double kObjectDensity = 1000.0;
/// PegInsertionSide's hole clearance [m] (ManiSkill's `clearance`): hole half width = peg radius + this.
inline constexpr double kPegHoleClearance = 0.003;

/// The task's snake_case name (pick_cube, push_cube, pull_cube, stack_cube, peg_insertion_side).
std::string_view task_name(TaskId task);
/// Task by name; throws actionshift::InputError (field "task") listing the valid names.
TaskId parse_task(std::string_view name);
/// Episode length in control steps: 50, or 100 for peg_insertion_side.
int task_horizon(TaskId task);
/// All five tasks, in declaration order.
std::span<const TaskId> all_tasks();

/// One named slice of a flat observation vector.
struct ObsField {
  std::string name;  ///< e.g. "qpos", "tcp_pose", "goal_pos"
  int offset{0};     ///< first index
  int width{0};      ///< number of entries
};

/// Machine-readable layout of a task's state observation (facts section 1 ordering).
/// Poses are world-frame position xyz then quaternion wxyz; booleans are 0/1.
class ObservationLayout {
 public:
  ObservationLayout() = default;
  /// Fields in order; offsets are assigned consecutively.
  explicit ObservationLayout(const std::vector<std::pair<std::string, int>>& fields);
  const std::vector<ObsField>& fields() const { return fields_; }
  int size() const { return size_; }
  /// The field named `name`, or nullptr.
  const ObsField* find(std::string_view name) const;
  /// The field named `name`; throws std::out_of_range naming it if absent.
  const ObsField& at(std::string_view name) const;
  /// `{"size":N,"fields":[{"name":..,"offset":..,"width":..},...]}`
  std::string to_json() const;

 private:
  std::vector<ObsField> fields_;
  int size_{0};
};

/// The observation layout of a task (the same object for every call).
const ObservationLayout& observation_layout(TaskId task);

/// Everything a success predicate or dense reward reads, in the world frame.
struct TaskSnapshot {
  Eigen::Matrix<double, 9, 1> qpos{Eigen::Matrix<double, 9, 1>::Zero()};  ///< 7 arm joints + 2 fingers
  Eigen::Matrix<double, 9, 1> qvel{Eigen::Matrix<double, 9, 1>::Zero()};
  Eigen::Isometry3d tcp{Eigen::Isometry3d::Identity()};                  ///< TCP pose
  std::array<Eigen::Isometry3d, 2> obj{Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()};  ///< cube / cubeA / peg, then cubeB / box
  std::array<Eigen::Vector3d, 2> obj_linvel{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  ///< [m/s]
  std::array<Eigen::Vector3d, 2> obj_angvel{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  ///< [rad/s]
  Eigen::Vector3d goal{Eigen::Vector3d::Zero()};  ///< pick: goal point; push/pull: goal disc centre
  bool grasped{false};         ///< is_grasping(obj[0]) with max_angle 85 deg
  bool grasped_strict{false};  ///< is_grasping(obj[0]) with max_angle 20 deg (peg reward)
  double peg_half_length{0.0}, peg_half_width{0.0};  ///< [m] peg box half sizes (L, r, r)
  double hole_half_width{0.0};                       ///< [m] r + 0.003 clearance
  Eigen::Vector3d hole_offset{Eigen::Vector3d::Zero()};  ///< hole centre in the box frame (0, cy, cz)
};

/// Success and normalised dense reward of one state.
struct TaskEvaluation {
  bool success{false};
  double reward{0.0};  ///< ManiSkill's normalized_dense reward (dense / max), in [0, 1]
};

/// Evaluate a state: success exactly as facts section 1, dense reward as ManiSkill's normalized_dense.
TaskEvaluation evaluate_task(TaskId task, const TaskSnapshot& s);

/// ManiSkill's is_grasping from the two finger contact forces (world frame, force ON each finger
/// from the object): each must be >= min_force and within max_angle of that finger's opening
/// direction (left +y of the hand, right -y).
bool is_grasping(const Eigen::Vector3d& force_left, const Eigen::Vector3d& force_right,
                 const Eigen::Vector3d& hand_y_axis, double min_force_n = 0.5, double max_angle_deg = 85.0);

/// One box of a task object, in the object's frame.
struct TaskBox {
  Eigen::Vector3d half_extents{Eigen::Vector3d::Zero()};  ///< [m]
  Eigen::Vector3d offset{Eigen::Vector3d::Zero()};        ///< [m] box centre in the object frame (axes aligned)
};

/// PegInsertionSide's box with a hole along its x axis: ManiSkill's `_build_box_with_hole`, four
/// static boxes around a square hole of half width `hole_half_width` whose centre sits at
/// `hole_offset` (0, cy, cz) in the box frame; the box's half depth and half height are the peg's
/// half length. The one copy of this geometry: the simulator collides with it, the renderer draws it.
std::array<TaskBox, 4> box_with_hole(double peg_half_length, double hole_half_width, const Eigen::Vector3d& hole_offset);

/// One task object as spawned: dynamic when mass > 0, static otherwise.
struct TaskObject {
  std::vector<TaskBox> boxes;
  double mass{0.0};  ///< [kg]
  Eigen::Vector3d position{Eigen::Vector3d::Zero()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
};

/// What a task's spawn draws for one episode: its objects (index 0: cube / cube A / peg; 1: cube B /
/// box) and the episode parameters the observation, success and reward read.
struct TaskEpisode {
  std::vector<TaskObject> objects;
  Eigen::Vector3d goal{Eigen::Vector3d::Zero()};
  double peg_half_length{0.0}, peg_half_width{0.0}, hole_half_width{0.0};
  Eigen::Vector3d hole_offset{Eigen::Vector3d::Zero()};
};

/// Which observation fields hold what a scripted policy reads (empty: the task has none).
struct TaskObsRoles {
  std::string_view object;    ///< pose of the manipulated object (cube, cube A, peg)
  std::string_view object_b;  ///< pose of the second object (cube B, the box's hole)
  std::string_view goal;      ///< goal position
  std::string_view grasped;   ///< is_grasped flag
};

/// A renderer's default view of the task (ManiSkill's human-render camera).
struct TaskCamera {
  Eigen::Vector3d eye{Eigen::Vector3d::Zero()};     ///< [m]
  Eigen::Vector3d target{Eigen::Vector3d::Zero()};  ///< [m]
};

/// Everything that makes a task, in one place (src/sim/task.cpp holds the five). Adding a task:
/// an enumerator in TaskId and a description in src/sim/task.cpp, plus its tests (docs/sim.md §5).
struct TaskDescription {
  TaskId id;
  std::string_view name;              ///< snake_case name (CLI, records, job ids)
  std::string_view maniskill_id;      ///< ManiSkill environment id, e.g. "PickCube-v1"
  std::string_view maniskill_source;  ///< where ManiSkill defines it (spawn, observation, success, reward)
  int horizon;                        ///< control steps per episode
  double rest_wrist;                  ///< [rad] joint 7 of the rest keyframe: pi/4 (panda) or -pi/4 (panda_wristcam)
  double gate0_floor;                 ///< reference competence floor of a backbone (Gate 0)
  const ObservationLayout& (*layout)();  ///< the flat state observation's fields
  TaskObsRoles roles;                 ///< the fields scripted policies read
  std::optional<TaskCamera> camera;   ///< the renderer's default view; empty: the renderer's default
  /// Draw one episode's objects and parameters from `rng`, in the documented order (after the robot's
  /// joint noise).
  void (*spawn)(Rng& rng, TaskEpisode& out);
  /// Write the task-specific fields of the observation (qpos, qvel and tcp_pose are written by Env).
  void (*observe)(const TaskSnapshot& s, const ObservationLayout& layout, Eigen::VectorXd& obs);
  /// Success exactly as ManiSkill, dense reward as ManiSkill's normalized_dense.
  TaskEvaluation (*evaluate)(const TaskSnapshot& s);
  /// Append the task's objects and goal marker to a scene (sim/scene.hpp) for renderers.
  void (*draw)(const TaskSnapshot& s, Scene& scene);
};

/// The description of a task (one static object per task).
const TaskDescription& task_description(TaskId task);

}  // namespace actionshift::sim
