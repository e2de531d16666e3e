#pragma once
/// \file
/// The Bullet Panda environment: an immutable, thread-shareable EnvModel (robot, task, settings)
/// and a per-worker Env (Bullet world, episode state, RNG) - the model/data split (immutable model, mutable per-episode data).
///
/// \code
///   auto model = actionshift::sim::EnvModel::make(actionshift::sim::TaskId::kPickCube);
///   actionshift::sim::Env env(model);              // one per thread
///   Eigen::VectorXd obs = env.reset(seed);          // initial state = pure function of seed
///   const auto& r = env.step(canonical_action);     // 7 numbers, docs/semantics.md §1
/// \endcode

#include "actionshift/core/vocabulary.hpp"
#include "actionshift/core/types.hpp"
#include "actionshift/sim/controller.hpp"
#include "actionshift/sim/physics_config.hpp"
#include "actionshift/sim/robot_description.hpp"
#include "actionshift/sim/task.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::sim {

namespace detail {
struct ModelData;
struct EnvImpl;
}  // namespace detail

/// Why an episode was ended early (fail closed, docs/sim.md §7). kNone = not ended by safety.
enum class SafetyFlag : std::uint8_t {
  kNone = 0,             ///< "none"
  kBadActionShape,       ///< "bad_action_shape": the action does not have 7 entries
  kNonfiniteAction,      ///< "nonfinite_action": NaN or inf in the action
  kActionOutOfRange,     ///< "action_out_of_range": |entry| > EnvConfig::max_action_magnitude
  kWorkspaceViolation,   ///< "workspace_violation": TCP left the declared workspace box
  kNonfiniteState,       ///< "nonfinite_state": NaN or inf in the simulated state
  kUnstableState,        ///< "unstable_state": joint or object speeds beyond any physical motion
};
/// The flags' names, as written into episode records ("none" is never written).
inline constexpr auto kSafetyFlags = make_vocabulary<SafetyFlag>(
    "safety flag", Vocabulary<SafetyFlag, 7>::Entry{SafetyFlag::kNone, "none"},
    Vocabulary<SafetyFlag, 7>::Entry{SafetyFlag::kBadActionShape, "bad_action_shape"},
    Vocabulary<SafetyFlag, 7>::Entry{SafetyFlag::kNonfiniteAction, "nonfinite_action"},
    Vocabulary<SafetyFlag, 7>::Entry{SafetyFlag::kActionOutOfRange, "action_out_of_range"},
    Vocabulary<SafetyFlag, 7>::Entry{SafetyFlag::kWorkspaceViolation, "workspace_violation"},
    Vocabulary<SafetyFlag, 7>::Entry{SafetyFlag::kNonfiniteState, "nonfinite_state"},
    Vocabulary<SafetyFlag, 7>::Entry{SafetyFlag::kUnstableState, "unstable_state"});
/// Name of a flag, as written into episode records ("none", "nonfinite_action", ...).
std::string_view safety_flag_name(SafetyFlag f);
/// The flag named `text`; throws actionshift::InputError(source, field, "unknown safety flag ...") otherwise.
SafetyFlag parse_safety_flag(std::string_view text, const std::string& source = "", const std::string& field = "safety_flags");

/// Axis-aligned box (world frame) the TCP must stay inside.
struct WorkspaceBox {
  Eigen::Vector3d lower{-0.5, -0.6, -0.05};  ///< [m]
  Eigen::Vector3d upper{0.5, 0.6, 0.8};      ///< [m]
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= lower.array()).all() && (p.array() <= upper.array()).all();
  }
};

/// Names of the robot parts the environment drives (defaults: the project's Panda URDF).
struct RobotNames {
  std::string tcp_link{"panda_hand_tcp"};
  std::string left_finger_joint{"panda_finger_joint1"};
  std::string right_finger_joint{"panda_finger_joint2"};
};

/// The fidelity profile of the default EnvConfig.
inline constexpr std::string_view kDefaultProfile = "maniskill";

/// Largest accepted EnvConfig::obs_noise (metres / radians): 10 cm of sensor noise is no sensor.
inline constexpr double kMaxObsNoise = 0.1;
/// Largest EnvConfig::horizon a run, a job or a Gate 0 accepts (control steps per episode).
inline constexpr int kMaxHorizon = 10000;
/// The one check of a horizon given by a user (`--horizon`, the experiment key, a job spec):
/// throws actionshift::InputError(source, field, "must be 0 (the task's) or 1 to 10000 control steps (got H)")
/// unless 0 <= horizon <= kMaxHorizon.
void check_horizon(long long horizon, const std::string& source, const std::string& field = "horizon");

/// Settings of an environment model. The defaults are the `maniskill` fidelity profile.
struct EnvConfig {
  std::string profile{kDefaultProfile};       ///< name of the fidelity profile these settings came from (recorded, hashed by jobs)
  PhysicsConfig physics;                      ///< Bullet and drive settings
  IkOptions ik;                               ///< controller IK
  int horizon{0};                             ///< control steps per episode; 0 = the task's horizon (calibration walks use more)
  WorkspaceBox workspace;                     ///< fail-closed TCP box
  double max_action_magnitude{100.0};         ///< |canonical entry| above this ends the episode (normalised units)
  double max_joint_speed{100.0};              ///< [rad/s] or [m/s]; above: unstable_state
  double max_object_speed{50.0};              ///< [m/s]; above: unstable_state
  Eigen::Vector3d robot_base{-0.615, 0.0, 0.0};  ///< robot base position in the world (identity orientation)
  RobotNames names;
  /// Observation (sensor) noise, OFF by default (docs/sim.md §6.1): sigma of zero-mean Gaussian noise
  /// on the observed TCP pose, metres on each position coordinate and the same number in radians on
  /// each component of a world-frame rotation vector turning the orientation; the tcp_to_* fields
  /// follow the noisy position. Drawn per episode from derive_seed({reset seed, stream tag}), a stream
  /// nothing else uses; the simulated state, task, reward and safety checks stay exact. 0 <= sigma <= kMaxObsNoise.
  double obs_noise{0.0};
};

/// Names of the fidelity profiles, default first: "maniskill", "ideal".
std::vector<std::string> profile_names();

/// The settings of a named fidelity profile (docs/sim.md "Fidelity profiles"):
/// - "maniskill" (default): what ManiSkill's GPU pd_ee_delta_pose path and PhysX drives do to the arm:
///   one damped-least-squares IK step per control step, implicit second-order PD drives with the link
///   inertia and the 100 N m force limit, joint limits enforced by the simulator;
/// - "ideal": IK iterated to convergence within the joint limits and a first-order velocity servo,
///   the project's original, cleaner response.
/// Throws actionshift::InputError (a std::invalid_argument) naming the valid profiles for any other name.
EnvConfig profile_config(std::string_view name);

/// Immutable description of one task's environment, shared by every worker thread.
class EnvModel {
 public:
  /// Build a model. `robot` defaults to panda_description(). Throws std::invalid_argument if the
  /// robot lacks the named TCP link or finger joints or has an arm chain other than 7 joints.
  static std::shared_ptr<const EnvModel> make(TaskId task, const EnvConfig& config = {},
                                              std::shared_ptr<const RobotDescription> robot = nullptr);
  ~EnvModel();

  TaskId task() const { return task_; }
  int horizon() const { return config_.horizon > 0 ? config_.horizon : task_horizon(task_); }  ///< control steps per episode
  const ObservationLayout& layout() const { return observation_layout(task_); }
  const EnvConfig& config() const { return config_; }
  const RobotDescription& robot() const { return *robot_; }
  const std::shared_ptr<const RobotDescription>& robot_ptr() const { return robot_; }  ///< shared description
  const KinematicChain& arm() const { return arm_; }                      ///< robot base -> TCP
  /// Rest joint configuration of the task (9): ManiSkill's keyframe (joint 7 = -pi/4 for stack and peg).
  Eigen::Matrix<double, 9, 1> rest_qpos() const;

  const detail::ModelData& data() const { return *data_; }  ///< implementation detail

 private:
  EnvModel() = default;
  TaskId task_{TaskId::kPickCube};
  EnvConfig config_;
  std::shared_ptr<const RobotDescription> robot_;
  KinematicChain arm_;
  std::unique_ptr<const detail::ModelData> data_;
};

/// What one control step returns. The observation never contains anything about a contract.
struct StepResult {
  Eigen::VectorXd obs;               ///< layout: EnvModel::layout(); always finite
  double reward{0.0};                ///< normalized dense reward
  bool success{false};               ///< evaluate() at this step
  bool terminated{false};            ///< = success (ManiSkill convention; runners may ignore it)
  bool truncated{false};             ///< elapsed_steps >= horizon
  SafetyFlag safety{SafetyFlag::kNone};  ///< set when the episode was ended by a safety check
  int elapsed_steps{0};
  /// Episode finished: horizon reached or a safety flag raised (termination on success is left to the runner).
  bool episode_over() const { return truncated || safety != SafetyFlag::kNone; }
};

/// Per-episode statistics (what an episode record needs).
struct EpisodeStats {
  bool success_once{false};     ///< success at any step
  bool success_at_end{false};   ///< success at the last step taken
  double episode_return{0.0};   ///< sum of rewards
  int steps{0};                 ///< control steps taken (an action rejected by a safety check is not simulated)
  SafetyFlag safety{SafetyFlag::kNone};
  int clipped_steps{0};         ///< steps where the controller clipped the command (|t_i| > 1, |r| > 1 or |g| > 1)
};

/// One worker's environment: owns its Bullet world, episode state and RNG. Not thread-safe; use
/// one Env per thread (they share the const EnvModel).
class Env {
 public:
  explicit Env(std::shared_ptr<const EnvModel> model);
  ~Env();
  Env(Env&&) noexcept;
  Env& operator=(Env&&) noexcept;

  const EnvModel& model() const;

  /// Start an episode. The initial state (robot noise, object poses, goals, peg geometry) is a pure
  /// function of `seed`; the physics world is rebuilt so no state of a previous episode survives.
  const Eigen::VectorXd& reset(std::uint64_t seed);

  /// One control step with a canonical action (7 entries). A wrong size, non-finite or
  /// out-of-range action ends the episode with a flag instead of being simulated.
  /// Stepping an episode that is over returns the last result unchanged.
  const StepResult& step(std::span<const double> canonical);
  const StepResult& step(const Action& canonical);

  /// End the current episode with a safety flag raised by a layer above (e.g. the hidden-contract
  /// wrapper rejecting a raw action). No-op if the episode is already over.
  const StepResult& abort(SafetyFlag flag);

  const StepResult& last() const;        ///< result of the last step (or of reset)
  const EpisodeStats& episode() const;   ///< statistics of the current episode

  // The state accessors below read the Bullet world, which holds the robot only after the first
  // reset: before it they (like step and abort) throw std::logic_error.
  Eigen::Isometry3d tcp_pose() const;    ///< TCP pose, world frame
  Eigen::Isometry3d tcp_pose_in_base() const;  ///< TCP pose, robot base frame (controller frame)
  TaskSnapshot snapshot() const;          ///< state the task predicates read
  Eigen::Matrix<double, 9, 1> qpos() const;
  /// Finger contact forces on (left, right) finger from the task's first object, last Bullet step [N].
  std::pair<Eigen::Vector3d, Eigen::Vector3d> finger_forces() const;

 private:
  std::unique_ptr<detail::EnvImpl> impl_;
};

}  // namespace actionshift::sim
