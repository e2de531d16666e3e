#include "actionshift/selftest/synthetic_robot.hpp"

#include <Eigen/Geometry>

namespace actionshift::selftest {

SyntheticRobot::SyntheticRobot(const Contract& hidden, const adapt::ResponseModel& model, std::uint64_t seed)
    : decoder_(hidden), model_(model), rng_(seed) {}

void SyntheticRobot::send(const Action& raw) {
  canonical_ = decoder_.step(raw, Mat3::Identity());
  Pose6 r = model_.expected(canonical_);
  for (int c = 0; c < kPoseDim; ++c) r[c] += model_.sigma[static_cast<std::size_t>(c)] * rng_.normal();
  pose_.position += r.head<3>();
  // orientation: q ← exp(rotvec) ⊗ q, so q_new ⊗ conj(q_old) recovers the rotation vector
  const Vec3 rv = r.tail<3>();
  const double angle = rv.norm();
  const Eigen::Quaterniond dq = angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, rv / angle)) : Eigen::Quaterniond::Identity();
  const Eigen::Quaterniond q(pose_.quaternion[0], pose_.quaternion[1], pose_.quaternion[2], pose_.quaternion[3]);
  const Eigen::Quaterniond qn = (dq * q).normalized();
  pose_.quaternion = {qn.w(), qn.x(), qn.y(), qn.z()};
}

void run(SelfTest& test, SyntheticRobot& robot) {
  test.begin(robot.pose());
  while (auto raw = test.next_probe()) {
    robot.send(*raw);
    test.observe(robot.pose());
  }
}

}  // namespace actionshift::selftest
