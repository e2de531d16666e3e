// pd_ee_delta_pose: command interpretation and damped-least-squares ik
#include "actionshift/sim/controller.hpp"

#include <algorithm>
#include <cmath>

namespace actionshift::sim {

double finger_target(double g) {
  const double c = std::clamp(g, -1.0, 1.0);
  return kFingerTargetOffset + kFingerTargetGain * c;
}

PoseCommand interpret_pose_command(const Eigen::Matrix<double, 6, 1>& pose) {
  PoseCommand out;
  for (int i = 0; i < 3; ++i) {
    const double c = std::clamp(pose(i), -1.0, 1.0);
    out.clipped = out.clipped || c != pose(i);
    out.delta_position(i) = kTranslationPerUnit * c;
  }
  Eigen::Vector3d r = pose.tail<3>();
  const double n = r.norm();
  if (n > 1.0) {
    r /= n;
    out.clipped = true;
  }
  out.delta_rotvec = kRotationPerUnit * r;
  return out;
}

Eigen::Isometry3d target_pose(const Eigen::Isometry3d& tcp_in_base, const PoseCommand& cmd) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = tcp_in_base.translation() + cmd.delta_position;
  t.linear() = so3_exp(cmd.delta_rotvec) * tcp_in_base.linear();
  return t;
}

IkResult solve_ik(const KinematicChain& chain, const Eigen::Ref<const Eigen::VectorXd>& q0,
                  const Eigen::Isometry3d& target, const IkOptions& options) {
  // levenberg-marquardt style clik: damped least-squares steps, each limited to max_step rad per
  // joint and clamped to the joint limits; a step that does not reduce the error is rejected and
  // the damping raised
  Eigen::Isometry3d tip;
  ChainJacobian jac;
  auto error_of = [&](const ChainVector& q, Eigen::Matrix<double, 6, 1>& err) {
    chain.fk_jacobian(q, tip, jac);
    err.head<3>() = target.translation() - tip.translation();
    err.tail<3>() = so3_log(target.linear() * tip.linear().transpose());
    return err.norm();
  };
  IkResult best;
  best.q = q0.cwiseMax(chain.lower()).cwiseMin(chain.upper());
  Eigen::Matrix<double, 6, 1> err;
  best.error = error_of(best.q, err);
  ChainJacobian best_jac = jac;
  Eigen::Matrix<double, 6, 1> best_err = err;
  double lambda = options.damping;
  for (int it = 1; it <= options.max_iterations && best.error >= options.tolerance; ++it) {
    Eigen::Matrix<double, 6, 6> a = best_jac * best_jac.transpose();
    a.diagonal().array() += lambda;
    const Eigen::Matrix<double, 6, 1> y = a.ldlt().solve(best_err);
    ChainVector dq = ChainVector::Zero(chain.dof());
    dq.noalias() += best_jac.transpose() * y;
    const double biggest = dq.cwiseAbs().maxCoeff();
    if (biggest > options.max_step) dq *= options.max_step / biggest;
    const ChainVector q = (best.q + dq).cwiseMax(chain.lower()).cwiseMin(chain.upper());
    const double e = error_of(q, err);
    if (e < best.error) {
      best.q = q;
      best.error = e;
      best.iterations = it;
      best_jac = jac;
      best_err = err;
      lambda = std::max(options.damping, lambda * 0.1);
    } else {
      lambda *= 10.0;
      if (lambda > 1e6) break;
    }
  }
  return best;
}

IkResult single_step_ik(const KinematicChain& chain, const Eigen::Ref<const Eigen::VectorXd>& q0,
                        const PoseCommand& cmd, const IkOptions& options) {
  Eigen::Isometry3d tip;
  ChainJacobian jac;
  chain.fk_jacobian(q0, tip, jac);
  Eigen::Matrix<double, 6, 1> dx;
  dx.head<3>() = cmd.delta_position;
  dx.tail<3>() = cmd.delta_rotvec;
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxChainDof, kMaxChainDof>;
  Square a = jac.transpose() * jac;
  a.diagonal().array() += options.damping;
  const ChainVector rhs = jac.transpose() * dx;
  IkResult out;
  out.q = q0 + a.ldlt().solve(rhs);
  out.iterations = 1;
  // residual of the linearised step (what the step leaves undone to first order)
  out.error = (dx - jac * (out.q - q0)).norm();
  return out;
}

}  // namespace actionshift::sim
