#pragma once
// `actionshift audit LOG` (issue 37, docs/audit.md): identify the action contract of a recorded log,
// and `actionshift record`: write such a log from the simulator for any job and contract. Plain
// functions; cli_selftest.cpp binds the options into the structs.
// audit exit codes: 0 PASS, 1 MISMATCH, 2 bad input or usage (as the rest of the CLI), 3 INCONCLUSIVE.

#include "cmd_run.hpp"
#include "commands.hpp"

#include "actionshift/selftest/audit.hpp"

#include <cstdint>
#include <optional>
#include <string>

namespace actionshift::cli {

inline constexpr int kAuditInconclusive = 3;  ///< audit's exit code for INCONCLUSIVE (2 is bad input)

struct AuditCliOptions {
  /// Bound directly: --confidence-floor, --misspec-ratio, --gain-tolerance (checked once, by
  /// selftest::validate). `declared` and `model` are set from the options below.
  selftest::AuditOptions audit;
  std::string log;                    ///< LOG: .csv, .jsonl, .h5/.hdf5 (ManiSkill or robomimic layout)
  std::string declared;               ///< --declared: contract argument or conventions JSON (file or inline); "" → the file's own, else identity
  std::string rotation;               ///< --rotation: axis_angle | euler_xyz | euler_zyx (overrides the declaration's)
  std::string gripper_range;          ///< --gripper-range: "[-1, 1]" | "[0, 1]" (also -1..1, 0..1)
  std::string action_kind;            ///< --action-kind: command | next_state | current_state
  std::string calibration;            ///< --calibration FILE (response model)
  std::string task;                   ///< --task T: the task's built-in calibration
  std::string profile{"maniskill"};   ///< --profile: with --task
  std::optional<long long> max_steps; ///< --max-steps N: audit only the first N transitions
  bool json{false};
};
int run_audit(const AuditCliOptions& o);

struct RecordOptions {
  CliJobOptions job;                  ///< the job (task, split, method, backbone, seed, episodes, obs noise, ...)
  long long contract{0};              ///< --contract I: the split's contract to record
  std::optional<long long> steps;     ///< --steps N: stop once N transitions are logged
  std::string out;                    ///< --out LOG (.csv, .jsonl, .h5)
  std::string layout{"maniskill"};    ///< --layout maniskill|robomimic for .h5
  std::string truth;                  ///< --truth FILE: write the hidden contract (conventions JSON) here
};
int run_record(const RecordOptions& o);

}  // namespace actionshift::cli
