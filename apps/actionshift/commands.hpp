#pragma once
// Option structs and entry points of the CLI's subcommands. The cli_*.cpp files (with main.cpp the only
// CLI11 translation units) bind the options into the structs and call these. Every entry point returns
// an ExitStatus.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::cli {

/// Exit codes shared by every command.
enum ExitStatus : int {
  kOk = 0,           ///< success
  kCheckFailed = 1,  ///< a check, gate or verdict failed
  kBadInput = 2,     ///< bad input or usage
  kInterrupted = 130,
};

/// "1 manifest", "3 manifests": a count and its noun for messages (regular plurals only).
inline std::string counted(std::size_t n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

/// `--robot URDF [--package NAME=DIR]...` of every command that builds an environment: another robot
/// description than the embedded Panda (loaded by cmd_robot.cpp; its content hash enters job ids).
struct RobotOptions {
  std::string urdf;                   ///< --robot FILE ("" → the embedded Panda)
  std::vector<std::string> packages;  ///< --package NAME=DIR, for package:// URIs
};

// ---- core (cmd_core.cpp)
struct ValidateOptions {
  std::vector<std::string> paths;  ///< manifest files or directories; empty: the built-in manifests
  bool quiet = false;              ///< only failures and the summary table
  bool json = false;               ///< machine-readable report
};
int run_validate(const ValidateOptions& o);

struct ContractOptions {
  std::string input;  ///< JSON text, a file path, or "-"/"" for stdin (one object per line)
};
int run_contract_hash(const ContractOptions& o);
int run_contract_decode(const ContractOptions& o);
int run_contract_encode(const ContractOptions& o);

struct SplitsGenerateOptions {
  std::string out_dir = "manifests";
  std::uint64_t seed = 20260718;
  std::vector<std::string> rules;  ///< empty: all
};
int run_splits_generate(const SplitsGenerateOptions& o);

// ---- bench env (cmd_bench_env.cpp, sim layer)
struct BenchEnvOptions {
  std::string task = "pick_cube";  ///< task name
  std::string profile = "maniskill";  ///< simulator fidelity profile
  long long steps = 12000;         ///< control steps per thread (short runs are dominated by machine noise)
  int threads = 0;                 ///< 0: all hardware threads
  bool json = false;               ///< one JSON object: task, threads, steps_per_s_one_thread, steps_per_s_all_threads
  bool raw_bullet = false;         ///< instead: Env::step against the same world stepped with no controller work
  RobotOptions robot;              ///< --robot/--package
};
int run_bench_env(const BenchEnvOptions& o);

// ---- compare (cmd_compare.cpp, eval layer)
// `actionshift compare RESULTS_DIR... [--pair 'CANDIDATE vs BASELINE']... [--pairs-from FILE] [--paper FILE]
//  [--out FILE]`: the comparison JSON (docs/formats.md "Comparison") on stdout or in FILE.
struct CompareOptions {
  std::vector<std::string> results_dirs;  ///< RESULTS_DIR... (positional, at least one)
  std::vector<std::string> pairs;         ///< --pair 'CANDIDATE vs BASELINE' (repeatable)
  std::string pairs_file;                 ///< --pairs-from FILE: one 'CANDIDATE vs BASELINE' per line
  std::string paper_file;                 ///< --paper FILE ("" → the built-in configs/paper/numbers.json)
  std::string out_file;                   ///< --out FILE ("" → stdout)
  bool common_episodes = false;           ///< --common-episodes: pair the episodes both cells hold
  bool across_backbones = false;          ///< --across-backbones: each pair per backbone and pooled over backbones
};
int run_compare(const CompareOptions& o);

}  // namespace actionshift::cli
