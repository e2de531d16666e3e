#pragma once
/// \file
/// Gate 0 for a backbone on a task (reference section 8.1; issue 4): competence (success_once of
/// the unwrapped runs with its Wilson 95 % interval against a floor) and wrapper parity (the same
/// initial states run through a HiddenContractEnv with the identity contract; the two-point rule
/// |delta| <= 0.02 and the overlapping-Wilson rule reported separately; parity passes if either
/// holds). Decision "advance" iff competence and parity pass, else "exclude".
///
/// \note The verdict file is {"schema_version","gate":"gate0","passed","cells":{"<backbone>/<task>":
/// {...,"verdict"}}}, the layout `actionshift gate check` reads.
/// Gate 0 lives here, next to its rollouts; the Wilson interval is core's (core/wilson.hpp).

#include "actionshift/core/wilson.hpp"
#include "actionshift/policy/policy.hpp"
#include "actionshift/policy/rollout.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::policy {

/// z of a two-sided 95 % interval as the reference computes it (core/wilson.hpp).
inline constexpr double kGate0Z95 = actionshift::kZ95;
/// Two-point parity tolerance (2 percentage points).
inline constexpr double kGate0ParityTolerance = 0.02;

/// Wilson score interval (not clamped, as the reference; core/wilson.hpp).
using Wilson = actionshift::WilsonInterval;
/// Throws std::invalid_argument "at least one episode is required" for total <= 0, and if
/// successes is outside [0, total].
Wilson wilson(std::int64_t successes, std::int64_t total);

/// Reference competence floor of a task: 0.20 for peg_insertion_side, 0.50 otherwise.
double gate0_floor(sim::TaskId task);

/// Which statistic must reach the floor.
enum class Gate0Rule {
  kWilsonLower,    ///< "wilson_lower": the Wilson lower bound (default; the project's eval default)
  kPointEstimate,  ///< "point_estimate": the success rate (the reference's rule)
};

struct Gate0Competence {
  double floor{0.5};
  Gate0Rule rule{Gate0Rule::kWilsonLower};
  Wilson interval;
  bool passed{false};
  std::string reason;  ///< "success {rate:.4f} below floor {floor:.4f}" or "success Wilson lower bound {lower:.4f} below floor {floor:.4f}"
};

struct Gate0Parity {
  Wilson reference, wrapped;
  double tolerance{kGate0ParityTolerance};
  double absolute_difference{0.0};
  bool two_point_rule{false};  ///< |delta| <= tolerance + 1e-12
  bool overlap_rule{false};    ///< max(lowers) <= min(uppers)
  bool passed{false};          ///< either rule
  std::string reason;          ///< "absolute success difference {d:.4f} exceeds {tol:.4f} and CIs do not overlap"
};

Gate0Competence gate0_competence(std::int64_t successes, std::int64_t total, double floor, Gate0Rule rule);
Gate0Parity gate0_parity(std::int64_t ref_successes, std::int64_t ref_total, std::int64_t wrap_successes,
                         std::int64_t wrap_total, double tolerance = kGate0ParityTolerance);

/// Settings of a Gate 0 run.
struct Gate0Run {
  std::string profile{"maniskill"};  ///< simulator fidelity profile (sim::profile_config)
  std::int64_t episodes{300};
  std::uint64_t seed{20260718};
  double floor{-1.0};  ///< < 0: gate0_floor(task)
  /// Control steps per episode; 0: the task's (50, peg_insertion_side 100). The reference evaluates its
  /// Diffusion Policy at 100 on every task. A verdict records it only when it is not the task's.
  int horizon{0};
  Gate0Rule rule{Gate0Rule::kWilsonLower};
  unsigned threads{0};
  std::function<void(std::int64_t, std::int64_t)> progress;  ///< (finished, total) over both runs
  std::shared_ptr<const sim::RobotDescription> robot;  ///< nullptr: the embedded Panda
  /// The robot's content hash (sim::load_robot_source's sha256); required with `robot`, so that the
  /// verdict names the description it certifies.
  std::string robot_sha256;
};

/// The checks run_gate0 makes before any episode (the CLI makes them before it builds the backbone):
/// at least one episode, a horizon in [0, sim::kMaxHorizon]. Throws actionshift::InputError.
void check_gate0_run(const Gate0Run& run);

/// A Gate 0 verdict for one backbone and task.
struct Gate0Verdict {
  std::string backbone, backbone_sha256, task;
  std::string profile{"maniskill"};  ///< simulator fidelity profile the episodes ran on
  std::string robot_sha256;          ///< content hash of a user-supplied robot description; "" for the embedded Panda
  std::uint64_t seed{0};
  std::int64_t episodes{0};
  int horizon{0};  ///< the run's horizon override; 0: the task's
  Gate0Competence competence;
  Gate0Parity identity_parity;
  std::int64_t success_at_end_unwrapped{0};
  std::int64_t flagged_unwrapped{0}, flagged_identity{0};  ///< episodes ended by a safety flag
  bool passed{false};
  std::string decision;  ///< "advance" | "exclude"
  std::string reason;    ///< first failing check ("competence: ...", "identity parity: ..."), or ""
};

/// Combine counts into a verdict.
Gate0Verdict gate0_verdict(std::string_view backbone, std::string_view backbone_sha256, sim::TaskId task,
                           const std::vector<EpisodeOutcome>& unwrapped, const std::vector<EpisodeOutcome>& identity,
                           double floor, Gate0Rule rule);

/// Run Gate 0: `episodes` unwrapped episodes and the same initial states identity-wrapped (env seed
/// derive_seed({seed, 0, k})), on all cores. Rethrows a policy failure.
Gate0Verdict run_gate0(const Policy& policy, const Gate0Run& run);

/// Verdict file of several cells (deterministic: no timing, sorted keys). A cell's key is
/// "<backbone>/<task>", and "<backbone>/<task>@robot:<first 12 hex of the robot hash>" with a
/// user-supplied robot, whose cell also holds "robot": {"sha256": ...}.
nlohmann::json gate0_to_json(const std::vector<Gate0Verdict>& verdicts);
/// "wilson_lower" | "point_estimate"; parse throws actionshift::InputError (field "rule").
std::string_view gate0_rule_name(Gate0Rule rule);
Gate0Rule parse_gate0_rule(std::string_view name);

}  // namespace actionshift::policy
