// observation access shared by every policy
#include "actionshift/policy/policy.hpp"

#include "actionshift/sim/kinematics.hpp"

#include <stdexcept>
#include <string>

namespace actionshift::policy {

Eigen::Isometry3d ObservationView::pose(const Eigen::Ref<const Eigen::VectorXd>& obs, int offset) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = obs.segment<3>(offset);
  t.linear() = sim::quat_wxyz_to_rotation(obs.segment<4>(offset + 3));
  return t;
}

void check_observation(const Eigen::Ref<const Eigen::VectorXd>& obs, sim::TaskId task) {
  const int expected = sim::observation_layout(task).size();
  if (obs.size() != expected)
    throw std::invalid_argument("observation has " + std::to_string(obs.size()) + " entries, expected " +
                                std::to_string(expected) + " for task " + std::string(sim::task_name(task)));
}

}  // namespace actionshift::policy
