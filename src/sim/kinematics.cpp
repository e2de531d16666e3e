// serial-chain kinematics over a RobotDescription
#include "actionshift/sim/kinematics.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace actionshift::sim {

KinematicChain::KinematicChain(const RobotDescription& desc, std::string_view tip) {
  // collect joints from tip up to the root
  std::vector<int> path;
  for (int l = desc.link_index(tip); l != desc.root;) {
    const int j = desc.parent_joint(l);
    if (j < 0) break;
    path.push_back(j);
    l = desc.joints[static_cast<std::size_t>(j)].parent;
  }
  // walk root -> tip accumulating fixed transforms between movable joints
  Eigen::Isometry3d pending = Eigen::Isometry3d::Identity();
  for (auto it = path.rbegin(); it != path.rend(); ++it) {
    const JointDescription& jd = desc.joints[static_cast<std::size_t>(*it)];
    pending = pending * jd.origin;
    if (!jd.movable()) continue;
    Step s;
    s.rot = pending.linear();
    s.trans = pending.translation();
    s.axis = jd.axis;
    s.prismatic = jd.type == JointDescription::Type::kPrismatic;
    steps_.push_back(s);
    joint_indices_.push_back(*it);
    pending = Eigen::Isometry3d::Identity();
  }
  if (dof() > kMaxChainDof)
    throw std::invalid_argument("kinematic chain to '" + std::string(tip) + "' has " + std::to_string(dof()) +
                                " movable joints, at most " + std::to_string(kMaxChainDof) + " supported");
  tail_rot_ = pending.linear();
  tail_trans_ = pending.translation();
  lower_.resize(dof());
  upper_.resize(dof());
  for (int i = 0; i < dof(); ++i) {
    const auto& jd = desc.joints[static_cast<std::size_t>(joint_indices_[static_cast<std::size_t>(i)])];
    lower_(i) = jd.lower;
    upper_(i) = jd.upper;
  }
}

Eigen::Isometry3d KinematicChain::fk(const Eigen::Ref<const Eigen::VectorXd>& q) const {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < dof(); ++i) {
    const Step& s = steps_[static_cast<std::size_t>(i)];
    p += r * s.trans;
    r = r * s.rot;
    if (s.prismatic)
      p += r * (s.axis * q(i));
    else
      r = r * Eigen::AngleAxisd(q(i), s.axis).toRotationMatrix();
  }
  p += r * tail_trans_;
  r = r * tail_rot_;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() = p;
  return t;
}

void KinematicChain::fk_jacobian(const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Isometry3d& tip,
                                 ChainJacobian& jac) const {
  Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxChainDof> axes(3, dof()), origins(3, dof());
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < dof(); ++i) {
    const Step& s = steps_[static_cast<std::size_t>(i)];
    p += r * s.trans;
    r = r * s.rot;
    axes.col(i) = r * s.axis;
    origins.col(i) = p;
    if (s.prismatic)
      p += axes.col(i) * q(i);
    else
      r = r * Eigen::AngleAxisd(q(i), s.axis).toRotationMatrix();
  }
  p += r * tail_trans_;
  r = r * tail_rot_;
  tip.setIdentity();
  tip.linear() = r;
  tip.translation() = p;
  jac.resize(6, dof());
  for (int i = 0; i < dof(); ++i) {
    const Eigen::Vector3d a = axes.col(i);
    if (steps_[static_cast<std::size_t>(i)].prismatic) {
      jac.block<3, 1>(0, i) = a;
      jac.block<3, 1>(3, i).setZero();
    } else {
      jac.block<3, 1>(0, i) = a.cross(p - origins.col(i));
      jac.block<3, 1>(3, i) = a;
    }
  }
}

Eigen::Matrix3d so3_exp(const Eigen::Vector3d& rotvec) {
  const double angle = rotvec.norm();
  if (angle < 1e-300) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, rotvec / angle).toRotationMatrix();
}

Eigen::Vector3d so3_log(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.axis() * aa.angle();
}

Eigen::Vector4d matrix_to_quat_wxyz(const Eigen::Matrix3d& r) {
  Eigen::Quaterniond q(r);
  q.normalize();
  Eigen::Vector4d out(q.w(), q.x(), q.y(), q.z());
  if (out(0) < 0.0) out = -out;
  return out;
}

Eigen::Matrix3d quat_wxyz_to_rotation(const Eigen::Vector4d& q) {
  return Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();
}

Eigen::Isometry3d franka_dh_flange(const Eigen::Matrix<double, 7, 1>& q) {
  // craig convention: rot_x(alpha) trans_x(a) rot_z(theta) trans_z(d)
  constexpr double kPi = 3.14159265358979323846;
  const double a[8] = {0, 0, 0, 0.0825, -0.0825, 0, 0.088, 0};
  const double d[8] = {0.333, 0, 0.316, 0, 0.384, 0, 0, 0.107};
  const double alpha[8] = {0, -kPi / 2, kPi / 2, kPi / 2, -kPi / 2, kPi / 2, kPi / 2, 0};
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 8; ++i) {
    const double theta = i < 7 ? q(i) : 0.0;
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    step.rotate(Eigen::AngleAxisd(alpha[i], Eigen::Vector3d::UnitX()));
    step.translate(Eigen::Vector3d(a[i], 0, 0));
    step.rotate(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()));
    step.translate(Eigen::Vector3d(0, 0, d[i]));
    t = t * step;
  }
  return t;
}

}  // namespace actionshift::sim
