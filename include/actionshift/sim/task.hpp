#pragma once
/// \file
/// The five ManiSkill3 table-top tasks: names, horizons, observation layouts, and their success
/// predicates and dense rewards as pure functions of a state snapshot (docs/sim.md §5; docs/reference.md, "Panda and tasks").

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::sim {

enum class TaskId {
  kPickCube,          ///< "pick_cube": lift the cube to a goal point (horizon 50)
  kPushCube,          ///< "push_cube": push the cube onto a goal disc 0.2 m further in +x (horizon 50)
  kPullCube,          ///< "pull_cube": pull the cube onto a goal disc 0.2 m back in -x (horizon 50)
  kStackCube,         ///< "stack_cube": put cube A on cube B and let go (horizon 50)
  kPegInsertionSide,  ///< "peg_insertion_side": insert the peg sideways into the box hole (horizon 100)
};

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

}  // namespace actionshift::sim
