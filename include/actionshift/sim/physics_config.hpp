#pragma once
/// \file
/// Simulation settings of the Bullet Panda (docs/sim.md explains every default).

#include <cmath>

namespace actionshift::sim {

/// How the arm's joint drives turn joint position targets into motion.
enum class ArmDrive {
  /// PhysX-style second-order PD drive (the `maniskill` profile): torque K (q* - q) - D qdot, solved
  /// implicitly with the arm's joint-space inertia and clipped to the force limit, so the arm carries
  /// momentum from one control step into the next and saturates on large commands.
  kImplicitPd,
  /// First-order velocity servo qdot* = (K / D)(q* - q) (the `ideal` profile): the dominant mode of the
  /// overdamped PD without the link inertia; each control step's motion depends on that step's target only.
  kVelocityServo,
};

/// Physics and drive settings. Defaults reproduce ManiSkill's `panda` + pd_ee_delta_pose intent
/// with the Bullet settings that make a grasp hold (docs/reference.md, "Bullet settings"; docs/sim.md §2).
struct PhysicsConfig {
  double control_dt_s{0.05};          ///< one control step (20 Hz)
  int sim_steps_per_control{5};       ///< 100 Hz simulation steps per control step
  int substeps_per_sim_step{1};       ///< Bullet steps per simulation step (1: 10 ms physics; 2: 5 ms, see docs/sim.md)
  int solver_iterations{15};          ///< sequential-impulse iterations per Bullet step
  double gravity{9.81};               ///< [m/s^2]
  bool gravity_compensation{true};    ///< cancel gravity on every robot link exactly (ManiSkill disables it)
  double drive_stiffness{1000.0};     ///< K of ManiSkill's joint PD drive [N m/rad] or [N/m]
  double drive_damping{100.0};        ///< D of ManiSkill's joint PD drive [N m s/rad] or [N s/m]
  double arm_force_limit{100.0};      ///< [N m] per arm joint (ManiSkill's drive force limit)
  double finger_force_limit{100.0};   ///< [N] per finger (ManiSkill); squeeze force is K*|q*-q| below it
  double default_friction{std::sqrt(0.3)};        ///< per-object Bullet friction; products give 0.3 between objects
  double finger_friction{1.15 / std::sqrt(0.3)};  ///< finger pads: product with default = 1.15 = PhysX avg(2.0, 0.3)
  bool finger_gear{true};             ///< btMultiBodyGearConstraint between the fingers (mimic)
  bool friction_anchors{true};        ///< CF_HAS_FRICTION_ANCHOR on fingers and objects
  double contact_processing_threshold{0.005};  ///< [m] manifold points farther apart than this make no solver rows
  ArmDrive arm_drive{ArmDrive::kImplicitPd};  ///< arm drive model (fingers always use the force-capped servo)
  bool arm_joint_limits{true};        ///< limit constraints on the arm joints too (PhysX enforces the URDF limits; fingers always)
};

}  // namespace actionshift::sim
