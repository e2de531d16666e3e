// pd_ee_delta_pose: command interpretation and damped-least-squares ik
#include "actionshift/sim/controller.hpp"

#include <algorithm>
#include <cmath>

namespace actionshift::sim {

double finger_target(double g) {
  const double c = std::clamp(g, -1.0, 1.0);
  return 0.015 + 0.025 * c;
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
  IkResult best;
  best.q = q0;
  best.error = INFINITY;
  ChainVector q = q0.cwiseMax(chain.lower()).cwiseMin(chain.upper());
  Eigen::Isometry3d tip;
  ChainJacobian jac;
  Eigen::Matrix<double, 6, 1> err;
  for (int it = 0; it <= options.max_iterations; ++it) {
    chain.fk_jacobian(q, tip, jac);
    err.head<3>() = target.translation() - tip.translation();
    err.tail<3>() = so3_log(target.linear() * tip.linear().transpose());
    const double e = err.norm();
    if (e < best.error) {
      best.error = e;
      best.q = q;
      best.iterations = it;
    }
    if (e < options.tolerance || it == options.max_iterations) break;
    Eigen::Matrix<double, 6, 6> a = jac * jac.transpose();
    a.diagonal().array() += options.damping;
    const Eigen::Matrix<double, 6, 1> y = a.ldlt().solve(err);
    q += jac.transpose() * y;
    q = q.cwiseMax(chain.lower()).cwiseMin(chain.upper());
  }
  return best;
}

}  // namespace actionshift::sim
