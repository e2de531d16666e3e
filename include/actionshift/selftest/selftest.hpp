#pragma once
/// \file Plug-and-verify self-test with the control loop inverted (docs/selftest.md; docs/reference.md, *Self-test*): the
/// caller's controller owns the robot. It asks for the next bounded probe, sends it, feeds back the
/// measured TCP pose, and after the budget asks for the verdict. Depends on core and the pool belief
/// only (no simulator).
///
/// \code
///   actionshift::selftest::Options o;            // expected = identity, library pool, entropy, budget 6
///   o.model = my_calibration.model();            // α, σ of the robot's TCP response per unit command
///   std::string err;
///   auto st = actionshift::selftest::SelfTest::create(o, &err);   // non-throwing twin
///   if (!st) { log(err); return; }
///   st->begin(read_tcp_pose());
///   while (auto raw = st->next_probe()) {        // nullopt once the budget is spent
///     robot.send(*raw);                          // |pose channel| <= amplitude, gripper held (or 0)
///     st->observe(read_tcp_pose());
///   }
///   auto v = st->verdict();                      // PASS / MISMATCH / INCONCLUSIVE, with reasons
/// \endcode

#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/types.hpp"
#include "actionshift/core/vocabulary.hpp"
#include "actionshift/selftest/verdict.hpp"

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::selftest {

enum class Strategy {
  kFixed,    ///< +amplitude on channels 0..5 in turn, then −amplitude, ... (reference `fixed_probe_pulse`)
  kEntropy,  ///< greedy one-step minimum expected posterior entropy over the 12 axis pulses (docs/reference.md, *Probes*,
             ///< calibrated and lag-aware preview), return-balanced unless Options::return_balanced is false
};
const char* to_string(Strategy s);  ///< "fixed" or "entropy"

/// Where the rotation used to decode `tool`-frame hypotheses comes from: the rotation mode
/// (core/vocabulary.hpp), kLive = the measured TCP orientation before each probe (the robot's live tool
/// frame), kIdentity = R = I (the reference's headline setting: tool equals base, so frame is not checked).
using FrameRotation = RotationMode;

/// A measured TCP pose in the robot base frame.
struct TcpPose {
  Vec3 position{Vec3::Zero()};                          ///< [m] (or the caller's unit)
  Eigen::Vector4d quaternion{1.0, 0.0, 0.0, 0.0};       ///< orientation, w x y z (need not be normalised)
  std::optional<Eigen::Vector2d> fingers;               ///< optional finger joint positions [m]
};

/// How the caller's gripper follows the gripper channel: each finger's position target is
/// `offset + gain·g` for a canonical gripper command g clipped to [−1, 1] (the simulator's controller:
/// offset 0.015 m, gain 0.025 m, docs/semantics.md §1).
struct GripperMap {
  double offset{0.0};  ///< finger target at g = 0 [m]
  double gain{1.0};    ///< finger target change per unit g [m], non-zero
};

/// Self-test settings (defaults: docs/reference.md, *Self-test*). Validated by validate(), by create() and by the
/// throwing constructor through the same checker.
struct Options {
  Contract expected;                ///< the wiring the policy assumes (default identity)
  std::vector<Contract> pool;       ///< declared candidate wirings; empty: the library pool (library.hpp)
                                    ///< `expected` is appended to either if absent
  adapt::ResponseModel model{{1, 1, 1, 1, 1, 1}, {0.05, 0.05, 0.05, 0.05, 0.05, 0.05}};  ///< response per unit canonical command
  Strategy strategy{Strategy::kEntropy};  ///< probe choice
  int budget{6};                    ///< probe steps, in [1, 10000]
  double amplitude{0.5};            ///< |raw| bound of every probe pose channel, in (0, 1]
  double confidence_floor{0.9};     ///< a field is resolved iff its confidence >= this, in (0, 1]
  double misspec_ratio{4.0};        ///< abstain if the MAP's fit ratio exceeds this, > 0
  /// If set, the threshold when the MAP has absolute targets (an absolute command's response is not
  /// what the delta-command gain calibration describes, so its residuals run on another scale), > 0.
  std::optional<double> misspec_ratio_absolute;
  FrameRotation frame_rotation{FrameRotation::kLive};  ///< rotation for tool-frame decoding
  double min_frame_angle{0.2};      ///< [rad] frame is checked only if the TCP orientation stays at least this far from identity
  /// Entropy strategy: a channel whose commanded raw sum is non-zero may only be pulsed back towards
  /// zero, so the summed raw command of every channel stays within ±amplitude. Under any delta wiring
  /// the TCP then stays within one pulse's response of its start, whatever the wiring (the reference's
  /// greedy choice can pulse the same direction every step and walk the arm to its reach limit, where
  /// the response saturates and mimics a scale change). The fixed pulses are balanced by construction.
  bool return_balanced{true};
  /// If set, every probe holds the fingers where begin() measured them: its gripper channel is the
  /// canonical command whose finger target is the measured position (mean of the two fingers, g
  /// clipped to [−1, 1]), encoded with the expected wiring's gripper polarity. Unset (or no finger
  /// positions at begin()): the gripper channel is 0, which a controller may map to a mid finger
  /// target. A wiring with another gripper polarity, or the zeros an actuation lag delivers first,
  /// still move the fingers; the report's finger travel shows it.
  std::optional<GripperMap> gripper;
};

/// Checks `o`; on failure returns false and sets `*err` (if non-null) to one line naming the field,
/// the rule and the value, e.g. "selftest options: budget must be in [1, 10000] (got 0)".
bool validate(const Options& o, std::string* err) noexcept;

class SelfTest {
 public:
  /// Throws std::invalid_argument with validate()'s message for invalid options.
  explicit SelfTest(const Options& options);
  /// Non-throwing twin for embedded use: nullopt and `*err` set for invalid options.
  static std::optional<SelfTest> create(const Options& options, std::string* err) noexcept;

  SelfTest(SelfTest&&) noexcept;
  SelfTest& operator=(SelfTest&&) noexcept;
  ~SelfTest();

  /// Start (or restart) the test at the robot's current pose. Throws std::invalid_argument for a
  /// non-finite pose or a zero quaternion.
  void begin(const TcpPose& start);
  /// Non-throwing twin of begin(): false and `*err` set for a bad pose.
  bool try_begin(const TcpPose& start, std::string* err) noexcept;

  /// The next raw 7-vector to send (|pose channel| <= amplitude; gripper channel the hold command of
  /// Options::gripper, exactly 0 without one), or nullopt
  /// once the budget is spent. Calling it again before observe() returns the same probe.
  /// Throws std::logic_error if begin() was not called.
  std::optional<Action> next_probe();

  /// The pose measured after the robot executed the last probe. Throws std::logic_error if no probe
  /// is outstanding, std::invalid_argument for a non-finite pose or a zero quaternion.
  void observe(const TcpPose& pose);
  /// Non-throwing twin of observe(): false and `*err` set (the sample is ignored).
  bool try_observe(const TcpPose& pose, std::string* err) noexcept;

  bool done() const noexcept;          ///< the budget is spent (every probe observed)
  int probes_observed() const noexcept;
  const Options& options() const noexcept;
  const std::vector<Contract>& pool() const noexcept;  ///< the declared pool, expected included
  /// Posterior over pool() (uniform before any observation).
  Eigen::VectorXd posterior() const;

  /// The evidence so far (usable before the budget is spent: fewer probes, less confidence).
  Evidence evidence() const;
  /// decide_verdict(evidence(), floor, ratio) plus the probe accounting.
  Verdict verdict() const;

 private:
  struct Impl;
  explicit SelfTest(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace actionshift::selftest
