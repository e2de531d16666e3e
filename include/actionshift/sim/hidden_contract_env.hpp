#pragma once
/// \file
/// The hidden-contract environment (docs/semantics.md, docs/sim.md §8): raw action -> core Decoder (frame rotation
/// = live TCP orientation, or identity) -> pd_ee_delta_pose controller. The agent-facing type has
/// no way to reach the contract; the evaluation-only OracleRecorder, built by the runner from the
/// same env, reads it.

#include "actionshift/core/contract.hpp"
#include "actionshift/core/types.hpp"
#include "actionshift/core/vocabulary.hpp"
#include "actionshift/sim/env.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace actionshift::eval::detail {
struct OracleAccess;  // the runner's factory of the oracle's view (src/eval/oracle_access.hpp, not installed)
}

namespace actionshift::sim {

namespace detail {
struct HiddenEnvImpl;
}
struct Scene;

/// Which rotation the decoder's `tool` frame uses: the rotation mode (core/vocabulary.hpp), kLive = the
/// TCP orientation in the robot base frame read before the step (default), kIdentity = R = I.
using FrameRotation = RotationMode;

/// Agent-facing environment under a hidden contract. Raw actions in (any length: a wrong length
/// ends the episode with bad_action_shape), observations out. Deliberately has no accessor for the
/// contract, the decoder or the decoded action (tests/sim/hidden_contract_env_test.cpp pins this).
class HiddenContractEnv {
 public:
  HiddenContractEnv(std::shared_ptr<const EnvModel> model, const Contract& contract,
                    FrameRotation rotation = FrameRotation::kLive);
  ~HiddenContractEnv();
  HiddenContractEnv(HiddenContractEnv&&) noexcept;
  HiddenContractEnv& operator=(HiddenContractEnv&&) noexcept;

  /// New episode: env reset (initial state = pure function of seed) and decoder reset.
  const Eigen::VectorXd& reset(std::uint64_t seed);
  /// One control step with a raw action. Non-finite, wrong-sized or out-of-range raw actions (and
  /// decoded actions) end the episode with a safety flag; nothing is simulated for them. Throws
  /// std::logic_error before the first reset.
  const StepResult& step(std::span<const double> raw);
  const StepResult& step(const Action& raw);

  const StepResult& last() const;
  const EpisodeStats& episode() const;
  const ObservationLayout& layout() const;
  TaskId task() const;
  int horizon() const;
  /// What a renderer draws (sim::scene_of of the wrapped environment): shapes and poses, nothing of
  /// the contract. Call it after reset().
  Scene scene() const;

 private:
  friend class OracleRecorder;
  std::unique_ptr<detail::HiddenEnvImpl> impl_;
};

/// Evaluation-only view of a HiddenContractEnv: the contract and what the oracle needs to encode.
/// Only the runner constructs it: the constructor takes a passkey whose constructor is private to
/// eval::detail::OracleAccess (the runner's factory, in a header that is not installed), so code
/// holding the agent-facing environment cannot build the view. tests/sim/oracle_view_negative.cpp
/// is compiled by CTest and must fail to compile. (C++ cannot stop a translation unit that
/// redefines the befriended class, an ODR violation; every well-formed path is closed.)
class OracleRecorder {
 public:
  /// The passkey: only eval::detail::OracleAccess can make one.
  class Key {
    Key() {}  // user-provided and private: no aggregate or value-initialisation route around it
    friend struct ::actionshift::eval::detail::OracleAccess;
  };

  OracleRecorder(const HiddenContractEnv& env, Key) : env_(&env) {}

  const Contract& contract() const;
  std::string contract_json() const;      ///< canonical JSON (hash input)
  /// Rotation the next decode will use (live TCP orientation in the base frame, or identity).
  Mat3 frame_rotation() const;
  /// The decoder's tracked target before the next step (absolute targets are offsets from it).
  Pose6 tracked_target() const;
  /// Raw action that the next step decodes to `canonical` (before lag): core encode() with the
  /// current R and tracked target.
  Action encode(const Action& canonical) const;
  /// Canonical action decoded at each step of this episode (before the lag FIFO).
  std::span<const Action> decoded() const;
  /// Action handed to the controller at each step of this episode (after the lag FIFO).
  std::span<const Action> applied() const;
  /// The wrapped environment, read-only (what a renderer draws: sim::scene_of(recorder.env())).
  const Env& env() const;

 private:
  const HiddenContractEnv* env_;
};

}  // namespace actionshift::sim
