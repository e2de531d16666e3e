#pragma once
// private: the Bullet world behind Env (never included from a public header)

#include "actionshift/sim/physics_config.hpp"
#include "actionshift/sim/robot_description.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

class btCollisionShape;
class btCompoundShape;
class btDefaultCollisionConfiguration;
class btCollisionDispatcher;
class btBroadphaseInterface;
class btMultiBodyConstraintSolver;
class btMultiBodyDynamicsWorld;
class btMultiBody;
class btMultiBodyJointMotor;
class btMultiBodyConstraint;
class btRigidBody;
class btMultiBodyLinkCollider;

namespace actionshift::sim::detail {

/// A box of a (possibly compound) object, in the object frame.
struct BoxPart {
  Eigen::Vector3d half_extents{Eigen::Vector3d::Zero()};
  Eigen::Isometry3d pose{Eigen::Isometry3d::Identity()};
};

/// A task object: dynamic when mass > 0, static otherwise.
struct ObjectSpec {
  std::vector<BoxPart> boxes;
  double mass{0.0};  // [kg], 0 = static
  Eigen::Vector3d position{Eigen::Vector3d::Zero()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
};

/// Robot articulation derived from a RobotDescription: one body per movable joint plus the base,
/// fixed links merged into their movable ancestor (the same layout pybullet's URDF import uses).
struct ArticulationLayout {
  struct Body {
    int parent{-1};                  // body index, -1 = base
    int joint{-1};                   // description joint index (movable)
    bool prismatic{false};
    double mass{0.0};
    Eigen::Vector3d inertia_diag{Eigen::Vector3d::Zero()};
    Eigen::Isometry3d link_to_bullet{Eigen::Isometry3d::Identity()};  // bullet frame (COM, principal axes) in the urdf link frame
    Eigen::Isometry3d joint_in_parent_link{Eigen::Isometry3d::Identity()};  // joint frame in the parent body's urdf frame
    Eigen::Vector3d axis{Eigen::Vector3d::UnitZ()};  // in the joint (= this body's urdf) frame
    std::vector<std::pair<CollisionGeometry, Eigen::Isometry3d>> shapes;  // geometry + pose in the body urdf frame
    std::string link_name;
  };
  Body base;                 // base link (fixed)
  std::vector<Body> bodies;  // movable bodies, parents first
  /// body index (-1 = base) and pose in that body's urdf frame, for every description link
  std::vector<std::pair<int, Eigen::Isometry3d>> link_body;
  std::vector<int> mimic_of;  // per body: body index it mimics, or -1

  explicit ArticulationLayout(const RobotDescription& desc);
  int body_of_joint(int joint) const;
};

class PhysicsWorld;

/// What the controller hands Bullet, recorded so the same world can later be stepped with no
/// controller work (the raw-Bullet limit of `actionshift bench env --raw-bullet`). While a recorder
/// is installed on a thread, every PhysicsWorld of that thread notes itself in `world` when it is
/// rebuilt and appends, for every Bullet step, 3 values per body: the arm drive's joint torque, the
/// motor's velocity target and the motor's impulse cap (0 where a body has none).
struct BulletInputRecorder {
  PhysicsWorld* world{nullptr};
  std::vector<double> inputs;
  bool recording{true};
};
/// Install `r` for the calling thread (nullptr removes it). Nothing is recorded otherwise.
void set_thread_input_recorder(BulletInputRecorder* r);

/// Per-worker Bullet world: the Panda multibody, the table, task objects.
class PhysicsWorld {
 public:
  PhysicsWorld(const RobotDescription& desc, const ArticulationLayout& layout, const PhysicsConfig& cfg,
               const Eigen::Isometry3d& base_pose, std::vector<int> finger_bodies);
  ~PhysicsWorld();
  PhysicsWorld(const PhysicsWorld&) = delete;
  PhysicsWorld& operator=(const PhysicsWorld&) = delete;

  /// Throw away the dynamics world and build a fresh one (determinism: no history survives).
  void rebuild(const std::vector<ObjectSpec>& objects, const Eigen::VectorXd& qpos);

  /// Joint position targets for the movable bodies (dim = num bodies).
  void set_targets(const Eigen::VectorXd& q_target) { q_target_ = q_target; }
  /// Advance one control step (sim_steps_per_control * substeps Bullet steps).
  void step_control();
  /// Values a recorder appends per control step (3 per body per Bullet step).
  int inputs_per_control_step() const { return 3 * num_dofs() * cfg_.sim_steps_per_control * cfg_.substeps_per_sim_step; }
  /// One control step with recorded inputs (inputs_per_control_step() values) and no controller work:
  /// the drive torques, motor targets and impulse caps are applied as recorded and Bullet is stepped.
  /// From the same rebuilt state it reproduces step_control's states bit for bit; the finger
  /// contact forces are not updated.
  void replay_control(const double* inputs);

  int num_dofs() const { return static_cast<int>(layout_.bodies.size()); }
  Eigen::VectorXd qpos() const;
  Eigen::VectorXd qvel() const;
  Eigen::Isometry3d object_pose(int i) const;
  Eigen::Vector3d object_linear_velocity(int i) const;
  Eigen::Vector3d object_angular_velocity(int i) const;
  /// Net contact force [N] on finger body `finger` from object `object` over the last Bullet step, world frame.
  Eigen::Vector3d finger_contact_force(int finger_slot, int object) const;
  /// World pose of the urdf frame of body b.
  Eigen::Isometry3d body_urdf_pose(int body) const;
  const Eigen::Isometry3d& base_pose() const { return base_pose_; }

 private:
  /// Remove every constraint, body and collider from the Bullet world (before destroying them).
  void detach_all();
  void build_robot(const Eigen::VectorXd& qpos);
  void compute_contact_forces();
  /// Joint-space inertia matrix of the multibody at its current state (num_dofs square) into mass_.
  void compute_mass_matrix();
  /// Arm torques of the implicit PD drive for one Bullet step of length h_, applied with addJointTorque
  /// (and written to record[3 * body] when `record` is non-null).
  void apply_implicit_pd(double* record = nullptr);
  bool is_finger(int body) const;

  const RobotDescription& desc_;
  const ArticulationLayout& layout_;
  PhysicsConfig cfg_;
  Eigen::Isometry3d base_pose_;
  std::vector<int> finger_bodies_;
  double h_{0.005};

  // shapes owned for the whole life of the env
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<btCompoundShape*> body_shapes_;  // per body, nullptr if no collision
  btCompoundShape* base_shape_{nullptr};
  std::unique_ptr<btCollisionShape> table_shape_;
  std::vector<std::unique_ptr<btCollisionShape>> object_shapes_;  // per episode

  // world (rebuilt each episode)
  std::unique_ptr<btDefaultCollisionConfiguration> collision_config_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btMultiBodyConstraintSolver> solver_;
  std::unique_ptr<btMultiBodyDynamicsWorld> world_;
  std::unique_ptr<btMultiBody> robot_;
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders_;
  std::vector<std::unique_ptr<btMultiBodyConstraint>> constraints_;
  std::vector<btMultiBodyJointMotor*> motors_;
  std::unique_ptr<btRigidBody> table_;
  std::vector<std::unique_ptr<btRigidBody>> objects_;

  Eigen::VectorXd q_target_;
  std::vector<int> arm_dofs_;       // bodies driven as arm joints (every non-finger body)
  Eigen::MatrixXd mass_;            // joint-space inertia scratch (num_dofs square)
  std::vector<Eigen::Vector3d> finger_forces_;  // [finger slot * num objects + object]
};

}  // namespace actionshift::sim::detail
