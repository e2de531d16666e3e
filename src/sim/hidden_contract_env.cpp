// hidden-contract wrapper: raw -> decoder -> controller; the oracle recorder reads it from outside
#include "actionshift/sim/hidden_contract_env.hpp"

#include "actionshift/core/decoder.hpp"
#include "actionshift/core/transforms.hpp"
#include "actionshift/sim/scene.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace actionshift::sim {

namespace detail {
struct HiddenEnvImpl {
  HiddenEnvImpl(std::shared_ptr<const EnvModel> model, const Contract& c, FrameRotation r)
      : env(std::move(model)), decoder(c), rotation(r) {
    decoded.reserve(static_cast<std::size_t>(env.model().horizon()));
    applied.reserve(static_cast<std::size_t>(env.model().horizon()));
  }
  Env env;
  Decoder decoder;
  FrameRotation rotation;
  std::vector<Action> decoded;
  std::vector<Action> applied;
  bool started{false};  // a first reset has built the world

  Mat3 frame_rotation() const {
    return rotation == FrameRotation::kLive ? Mat3(env.tcp_pose_in_base().linear()) : Mat3::Identity();
  }
};
}  // namespace detail

HiddenContractEnv::HiddenContractEnv(std::shared_ptr<const EnvModel> model, const Contract& contract,
                                     FrameRotation rotation)
    : impl_(std::make_unique<detail::HiddenEnvImpl>(std::move(model), contract, rotation)) {}
HiddenContractEnv::~HiddenContractEnv() = default;
HiddenContractEnv::HiddenContractEnv(HiddenContractEnv&&) noexcept = default;
HiddenContractEnv& HiddenContractEnv::operator=(HiddenContractEnv&&) noexcept = default;

const Eigen::VectorXd& HiddenContractEnv::reset(std::uint64_t seed) {
  impl_->decoder.reset_all();
  impl_->decoded.clear();
  impl_->applied.clear();
  const Eigen::VectorXd& obs = impl_->env.reset(seed);
  impl_->started = true;
  return obs;
}

const StepResult& HiddenContractEnv::step(const Action& raw) {
  return step(std::span<const double>(raw.data(), static_cast<std::size_t>(raw.size())));
}

const StepResult& HiddenContractEnv::step(std::span<const double> raw) {
  detail::HiddenEnvImpl& h = *impl_;
  if (!h.started) throw std::logic_error("HiddenContractEnv::step called before reset");
  if (h.env.last().episode_over()) return h.env.last();
  // the raw action is checked before it can touch the decoder state
  if (raw.size() != static_cast<std::size_t>(kActionDim)) return h.env.abort(SafetyFlag::kBadActionShape);
  Action a;
  for (int i = 0; i < kActionDim; ++i) {
    a(i) = raw[static_cast<std::size_t>(i)];
    if (!std::isfinite(a(i))) return h.env.abort(SafetyFlag::kNonfiniteAction);
  }
  const double limit = h.env.model().config().max_action_magnitude;
  if (a.cwiseAbs().maxCoeff() > limit) return h.env.abort(SafetyFlag::kActionOutOfRange);
  const Mat3 r = h.frame_rotation();
  h.decoded.push_back(decode(h.decoder.contract(), a, r, h.decoder.tracked_target()));
  const Action canonical = h.decoder.step(a, r);
  h.applied.push_back(canonical);
  return h.env.step(canonical);  // the env re-checks the decoded action (finite, range)
}

const StepResult& HiddenContractEnv::last() const { return impl_->env.last(); }
const EpisodeStats& HiddenContractEnv::episode() const { return impl_->env.episode(); }
const ObservationLayout& HiddenContractEnv::layout() const { return impl_->env.model().layout(); }
TaskId HiddenContractEnv::task() const { return impl_->env.model().task(); }
int HiddenContractEnv::horizon() const { return impl_->env.model().horizon(); }

const Contract& OracleRecorder::contract() const { return env_->impl_->decoder.contract(); }
std::string OracleRecorder::contract_json() const { return contract().to_json(); }
Mat3 OracleRecorder::frame_rotation() const { return env_->impl_->frame_rotation(); }
Pose6 OracleRecorder::tracked_target() const { return env_->impl_->decoder.tracked_target(); }
Action OracleRecorder::encode(const Action& canonical) const {
  return actionshift::encode(contract(), canonical, frame_rotation(), tracked_target());
}
std::span<const Action> OracleRecorder::decoded() const { return env_->impl_->decoded; }
std::span<const Action> OracleRecorder::applied() const { return env_->impl_->applied; }
const Env& OracleRecorder::env() const { return env_->impl_->env; }

Scene HiddenContractEnv::scene() const { return scene_of(impl_->env); }

}  // namespace actionshift::sim
