// The identifier adapter: acts on the contract an identifier predicts (osi, probe_osi, recurrent_osi)
#include "actionshift/adapt/identifier.hpp"

#include "actionshift/core/decoder.hpp"
#include "actionshift/core/transforms.hpp"

namespace actionshift::adapt {

IdentifierAdapter::IdentifierAdapter(std::shared_ptr<const IdentifierWeights> weights, IdentifierOptions options)
    : state_(std::move(weights)), options_(options) {
  sent_.reserve(64);
}

void IdentifierAdapter::begin_episode(std::uint64_t) {
  state_.reset();
  step_ = 0;
  estimate_.reset();
  sent_.clear();
  replica_.reset();
  last_ = {};
}

Action IdentifierAdapter::encode(const Action& canonical, const Mat3& R) {
  last_ = {};
  if (step_ < options_.probe_budget) {  // the fixed pulses of the belief methods: +a on channel k, gripper never actuated
    Action a = Action::Zero();
    a[step_ % kPoseDim] = (step_ / kPoseDim) % 2 == 0 ? options_.probe_amplitude : -options_.probe_amplitude;
    last_.probe = true;
    return a;
  }
  if (!estimate_) return canonical;  // pass-through evidence before the first estimate
  return actionshift::encode(*estimate_, canonical, R, replica_->tracked_target());
}

void IdentifierAdapter::re_estimate() {
  const Contract c = decode_logits(state_.logits());
  if (!estimate_ || !(c == *estimate_)) {
    estimate_ = c;
    replica_.emplace(c);  // the tracked target the wrapper holds if the estimate is the truth
    for (const auto& [raw, R] : sent_) replica_->step(raw, R);
  }
}

void IdentifierAdapter::observe(const Action& raw, const Pose6& response, const Mat3& R) {
  state_.feed(raw.head<6>(), response);
  sent_.emplace_back(raw, R);
  ++step_;
  if (replica_) replica_->step(raw, R);
  const int first = options_.probe_budget + options_.warmup;
  if (step_ < first) return;
  if (options_.freeze && estimate_) return;
  re_estimate();
}

}  // namespace actionshift::adapt
