#pragma once
// `actionshift selftest`: plug-and-verify self-test (issue 7, docs/selftest.md), as a plain function.
// Exit codes are the self-test's own: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input. run_selftest
// catches its own errors so that bad input is 3, not the CLI's generic 2.

#include "commands.hpp"
#include "actionshift/core/contract.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::cli {

inline constexpr int kSelftestBadInput = 3;  ///< selftest's exit code for bad input or usage

/// Default probe budget and amplitude of `--sim` (measured, docs/selftest.md §5).
inline constexpr int kSimDefaultBudget = 6;
inline constexpr double kSimDefaultAmplitude = 0.5;

struct SelftestOptions {
  std::string task = "pick_cube";           ///< task (sim backend) or label (synthetic)
  std::string demo;                          ///< a demo name; exclusive with hidden_contract
  std::string hidden_contract;               ///< contract argument; default: the expected contract
  std::string expected = "identity";         ///< contract argument
  bool sim = false;                          ///< probe the Bullet environment instead of the synthetic stand-in
  std::string profile = "maniskill";         ///< --sim: simulator fidelity profile
  std::string calibration;                   ///< --sim: calibration JSON file (default: the task's built-in one)
  std::string frame_rotation = "live";       ///< --sim: live | identity
  std::vector<std::string> pools;            ///< "library", a manifest name or file (repeatable; default below)
  std::string strategy = "entropy";          ///< fixed | entropy
  std::optional<int> budget;                 ///< default 6 (synthetic), kSimDefaultBudget (sim)
  std::optional<double> amplitude;           ///< default 0.5 (synthetic), kSimDefaultAmplitude (sim)
  double confidence_floor = 0.9;
  std::optional<double> misspec_ratio;      ///< default 4.0 (synthetic); --sim: the task's calibrated value
  std::string calibrate_misspec;             ///< --sim: measure the misspecification threshold, write it here
  std::uint64_t seed = 20260720;
  bool json = false;
  RobotOptions robot;                        ///< --sim: --robot/--package
};

/// A contract argument (--expected, --hidden-contract): a library name, MANIFEST:INDEX, a file with
/// contract JSON, or inline contract JSON. throws actionshift::InputError naming `option` and the
/// file (if any) for anything else. Public for the CLI tests and the fuzzer.
Contract resolve_contract_arg(const std::string& arg, const std::string& option);

/// Default --misspec-ratio of the synthetic stand-in (its noise model is exact).
inline constexpr double kSyntheticMisspecRatio = 4.0;
/// Default --misspec-ratio of --sim for a task without a calibrated value in configs/selftest/sim_misspec.json.
inline constexpr double kUncalibratedSimMisspecRatio = 4.0;
/// Seeds per in-pool wiring and safety margin of `selftest --sim --calibrate-misspec`.
inline constexpr int kMisspecCalibrationSeeds = 8;
inline constexpr double kMisspecCalibrationMargin = 1.5;

/// Runs the self-test and prints the report (text or JSON) on stdout. Returns 0/1/2 by verdict, 3 for
/// bad input (one "actionshift: error: ..." line on stderr).
int run_selftest(const SelftestOptions& o);

}  // namespace actionshift::cli
