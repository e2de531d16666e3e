#pragma once
/// \file
/// The `pd_ee_delta_pose` arm controller (docs/semantics.md §1, docs/sim.md §4): canonical pose delta -> TCP target pose
/// -> damped-least-squares IK -> joint position targets for the PD drives.

#include "actionshift/sim/kinematics.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace actionshift::sim {

/// Normalised action units: 1 = 0.1 m translation and 0.1 rad rotation per control step.
inline constexpr double kTranslationPerUnit = 0.1;  ///< [m]
inline constexpr double kRotationPerUnit = 0.1;     ///< [rad]

/// Finger joint target [m] for a gripper command g (clipped to [-1, 1]): 0.015 + 0.025 g.
inline constexpr double kFingerTargetOffset = 0.015;  ///< [m] at g = 0
inline constexpr double kFingerTargetGain = 0.025;    ///< [m] per unit g
double finger_target(double g);

/// Result of interpreting one canonical pose command (6 numbers).
struct PoseCommand {
  Eigen::Vector3d delta_position{Eigen::Vector3d::Zero()};  ///< [m], base frame, after clipping
  Eigen::Vector3d delta_rotvec{Eigen::Vector3d::Zero()};    ///< [rad], base-aligned axes about the TCP, after clipping
  bool clipped{false};                                      ///< any component was clipped
};

/// Clip and scale a canonical pose command: each translation component to [-1, 1], the rotation
/// vector to norm <= 1, then 1 unit = 0.1 m / 0.1 rad. NO ManiSkill rotation sign flip.
PoseCommand interpret_pose_command(const Eigen::Matrix<double, 6, 1>& pose);

/// Target TCP pose (base frame) for a command: p + dp, Exp(dr) R.
Eigen::Isometry3d target_pose(const Eigen::Isometry3d& tcp_in_base, const PoseCommand& cmd);

/// How a TCP target becomes joint targets.
enum class IkMode {
  /// ManiSkill's GPU `pd_ee_delta_pose` path (the `maniskill` profile): ONE damped-least-squares
  /// step at the current joints, dq = (J^T J + damping I)^-1 J^T dx with dx = [dp; dtheta], no
  /// iteration and no joint-limit clamping (the simulator's joint limits act instead).
  kSingleStep,
  /// Iterate the damped least squares to convergence within the joint limits (the `ideal` profile).
  kConverged,
};

/// Damped-least-squares settings.
struct IkOptions {
  IkMode mode{IkMode::kSingleStep};  ///< one step (ManiSkill) or converged
  int max_iterations{30};    ///< damped-least-squares iterations
  double damping{1e-4};      ///< lambda: ManiSkill's 1e-4 for the single step; the minimum lambda^2 added to J J^T when converging
  double max_step{0.2};      ///< [rad] largest joint change per iteration
  double tolerance{1e-10};   ///< stop when |error| (m and rad stacked) is below this
};

/// Result of an IK solve.
struct IkResult {
  ChainVector q;                 ///< joint solution, within the chain's limits
  double error{0.0};             ///< final pose error norm ([m] and [rad] stacked)
  int iterations{0};
};

/// Solve for joints reaching `target` (root frame) from q0: Levenberg-Marquardt style CLIK, each
/// step limited to IkOptions::max_step per joint and clamped to the joint limits. Returns the best
/// iterate seen (q0 clamped if nothing improves). Allocation-free.
IkResult solve_ik(const KinematicChain& chain, const Eigen::Ref<const Eigen::VectorXd>& q0,
                  const Eigen::Isometry3d& target, const IkOptions& options = {});

/// ManiSkill's single damped-least-squares step for a pose command at joints q0:
/// q0 + (J^T J + options.damping I)^-1 J^T [dp; dtheta], J the 6 x dof TCP Jacobian in the root frame.
/// Not clamped to the joint limits. Allocation-free.
IkResult single_step_ik(const KinematicChain& chain, const Eigen::Ref<const Eigen::VectorXd>& q0,
                        const PoseCommand& cmd, const IkOptions& options = {});

}  // namespace actionshift::sim
