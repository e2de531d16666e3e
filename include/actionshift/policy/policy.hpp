#pragma once
/// \file
/// The frozen-policy interface (docs/backbones.md): a `Policy` maps a task's flat state observation to
/// a canonical action (docs/semantics.md §1: 7 numbers, +-1 = +-0.1 m / +-0.1 rad per 0.05 s control step,
/// robot base frame, gripper +1 open / -1 closed). Policies are per-episode state objects: `reset()`
/// at episode start, then `act()` once per control step; `clone()` gives an independent copy for
/// another worker thread.
///
/// \code
///   auto policy = actionshift::policy::make_policy("expert", actionshift::sim::TaskId::kPickCube);
///   policy->reset();
///   actionshift::Action a = policy->act(env.reset(seed));
/// \endcode

#include "actionshift/core/types.hpp"
#include "actionshift/sim/task.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <string_view>

namespace actionshift::policy {

/// A frozen policy: observation -> canonical action.
class Policy {
 public:
  virtual ~Policy() = default;

  /// Start of an episode: clear any per-episode memory (phase, action history).
  virtual void reset() = 0;
  /// Canonical action for `obs` (layout: the task's sim::ObservationLayout). Called once per step.
  /// Throws std::invalid_argument if obs has the wrong size; std::runtime_error if the policy
  /// cannot produce an action (an external process died or replied garbage).
  virtual Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) = 0;
  /// Backbone name as used on the command line (e.g. "expert", "mlp", "external:python3 p.py").
  virtual std::string name() const = 0;
  /// 64-hex SHA-256 identifying the backbone: of a version string for scripted experts, of the
  /// weight file for MLPs, of the command string for external policies.
  virtual std::string sha256() const = 0;
  /// Task the policy acts on.
  virtual sim::TaskId task() const = 0;
  /// A fresh, independent policy of the same kind (one per worker thread); its state is reset.
  virtual std::unique_ptr<Policy> clone() const = 0;
};

/// Named, offset-resolved read access to a task's flat observation vector (no string lookups per
/// step once constructed). Poses are world-frame position xyz then quaternion wxyz.
class ObservationView {
 public:
  /// Throws std::out_of_range naming the field if the layout lacks it (see ObservationLayout::at).
  explicit ObservationView(const sim::ObservationLayout& layout) : layout_(&layout) {}

  /// Offset of field `name` (throws std::out_of_range if absent).
  int offset(std::string_view name) const { return layout_->at(name).offset; }
  const sim::ObservationLayout& layout() const { return *layout_; }

  /// 3-vector at `offset`.
  static Eigen::Vector3d vec3(const Eigen::Ref<const Eigen::VectorXd>& obs, int offset) {
    return obs.segment<3>(offset);
  }
  /// Pose (xyz, wxyz) starting at `offset`, as an isometry.
  static Eigen::Isometry3d pose(const Eigen::Ref<const Eigen::VectorXd>& obs, int offset);

 private:
  const sim::ObservationLayout* layout_;
};

/// Throws std::invalid_argument "observation has N entries, expected M for task T" on a size mismatch.
void check_observation(const Eigen::Ref<const Eigen::VectorXd>& obs, sim::TaskId task);

}  // namespace actionshift::policy
