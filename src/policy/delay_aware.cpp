// delay-aware expert: lag estimate from its own history + Smith predictor around the expert
#include "actionshift/policy/delay_aware.hpp"

#include "actionshift/core/hash.hpp"
#include "actionshift/policy/expert.hpp"

#include <algorithm>
#include <cmath>

namespace actionshift::policy {
namespace {

// offsets of the TCP and the moved object in a task's observation
struct Offsets {
  int tcp{0}, obj{0}, qpos{0}, grasped{-1};
};

Offsets offsets(sim::TaskId task) {
  const sim::TaskDescription& d = sim::task_description(task);
  const auto& l = d.layout();
  Offsets o;
  o.tcp = l.at("tcp_pose").offset;
  o.qpos = l.at("qpos").offset;
  o.obj = l.at(d.roles.object).offset;
  if (!d.roles.grasped.empty()) o.grasped = l.at(d.roles.grasped).offset;
  return o;
}

}  // namespace

DelayAwareExpert::DelayAwareExpert(sim::TaskId task, std::optional<int> known_lag) : task_(task), known_lag_(known_lag) {
  reset();
}

void DelayAwareExpert::reset() {
  for (auto& a : history_) a.setZero();
  evidence_.fill(0.0);
  steps_ = 0;
  lag_ = known_lag_.value_or(0);
}

std::string DelayAwareExpert::sha256() const {
  return sha256_hex(std::string(kDelayAwareExpertVersion) + "/" + std::string(sim::task_name(task_)));
}

std::unique_ptr<Policy> DelayAwareExpert::clone() const { return std::make_unique<DelayAwareExpert>(task_, known_lag_); }

void DelayAwareExpert::override_last_action(const Action& executed) { history_[0] = executed; }

Eigen::VectorXd DelayAwareExpert::predict_observation(const Eigen::Ref<const Eigen::VectorXd>& obs, int lag) const {
  Eigen::VectorXd pred = obs;
  if (lag <= 0) return pred;
  const Offsets o = offsets(task_);
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  for (int j = 0; j < std::min(lag, kMaxPredictedLag); ++j)
    shift += kResponseGain * 0.1 * history_[static_cast<std::size_t>(j)].head<3>().cwiseMax(-1.0).cwiseMin(1.0);
  const Eigen::Vector3d tcp = obs.segment<3>(o.tcp);
  const Eigen::Vector3d obj = obs.segment<3>(o.obj);
  const double opening = obs(o.qpos + 7) + obs(o.qpos + 8);
  // the object moves with the tcp when held, or (push/pull) when the fingers are against it
  bool attached = false;
  if (o.grasped >= 0) attached = obs(o.grasped) > 0.5;
  else if (task_ == sim::TaskId::kPushCube || task_ == sim::TaskId::kPullCube) {
    const double dir = task_ == sim::TaskId::kPushCube ? 1.0 : -1.0;
    const Eigen::Vector3d rel = tcp - obj;
    attached = dir * rel.x() < 0.0 && dir * rel.x() > -0.05 && std::abs(rel.y()) < 0.015 && tcp.z() < 0.04;
    if (attached) shift = Eigen::Vector3d(dir * std::max(0.0, dir * shift.x()), 0.0, 0.0);
    pred.segment<3>(o.tcp) += shift;
    if (attached) pred.segment<3>(o.obj) += shift;
    else pred.segment<3>(o.tcp) = tcp + shift;
    return pred;
  } else
    attached = (tcp - obj).norm() < 0.015 && opening > 0.025 && opening < 0.055;
  pred.segment<3>(o.tcp) += shift;
  if (attached) pred.segment<3>(o.obj) += shift;
  return pred;
}

Action DelayAwareExpert::act(const Eigen::Ref<const Eigen::VectorXd>& obs) {
  check_observation(obs, task_);
  const Offsets o = offsets(task_);
  const Eigen::Vector3d tcp = obs.segment<3>(o.tcp);
  // lag evidence: observed displacement vs the action emitted L+1 steps ago
  if (steps_ > 0) {
    const Eigen::Vector3d moved = tcp - last_tcp_;
    for (int lag = 0; lag <= kMaxPredictedLag; ++lag) {
      const Eigen::Vector3d cmd = lag < steps_ ? Eigen::Vector3d(history_[static_cast<std::size_t>(lag)].head<3>().cwiseMax(-1.0).cwiseMin(1.0))
                                               : Eigen::Vector3d::Zero();
      evidence_[static_cast<std::size_t>(lag)] += (moved - kResponseGain * 0.1 * cmd).squaredNorm();
    }
  }
  if (known_lag_) lag_ = *known_lag_;
  else lag_ = static_cast<int>(std::min_element(evidence_.begin(), evidence_.end()) - evidence_.begin());
  const Action a = expert_action(task_, predict_observation(obs, lag_));
  // remember: most recent first
  for (std::size_t j = history_.size() - 1; j > 0; --j) history_[j] = history_[j - 1];
  history_[0] = a;
  last_tcp_ = tcp;
  ++steps_;
  return a;
}

}  // namespace actionshift::policy
