#pragma once
// The CLI11 side of the actionshift command line, shared by main.cpp (the dispatcher) and the
// cli_*.cpp files, each of which registers one group of subcommands. These are the only translation
// units that include CLI11 (slow to compile); the cmd_*.cpp files that implement the commands are
// plain functions over option structs and never see it.

#include "commands.hpp"

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace actionshift::cli {

struct CliJobOptions;  // cmd_run.hpp

/// What a registration function gets: the action the parsed command will run (set by its
/// callback), storage for the option structs the subcommands bind (they must outlive registration),
/// and what several help texts share.
struct CliContext {
  std::function<int()> action;  ///< set by the callback of the subcommand that was parsed
  std::string task_list;        ///< the tasks' names, comma-separated (sim/task.hpp)
  std::string method_list;      ///< the method registry's names, comma-separated
  int argc{0};
  char** argv{nullptr};

  /// A value that lives as long as this context (an options struct a subcommand binds).
  template <class T, class... Args>
  T& make(Args&&... args) {
    auto p = std::make_shared<T>(std::forward<Args>(args)...);
    storage_.push_back(p);
    return *p;
  }

 private:
  std::vector<std::shared_ptr<void>> storage_;
};

// Validators every group uses (main.cpp).
extern const CLI::Validator kSeed;      ///< an integer in [0, 2**64), checked as text
extern const CLI::Validator kNotEmpty;  ///< an empty value given on purpose is an error
extern const CLI::Validator kNotNan;    ///< CLI::Range lets NaN through
extern const CLI::Validator kProfile;   ///< a simulator fidelity profile name

/// --robot URDF [--package NAME=DIR]... on a command that builds an environment (`makes_jobs`: run
/// and plan, whose job ids hash the description). main.cpp.
void add_robot_options(CLI::App* cmd, RobotOptions& r, bool makes_jobs = false);
/// The options that name one job: `run`, `render` and `record` share them, so a render reaches the
/// run's job id. cli_eval.cpp.
void add_job_options(CliContext& ctx, CLI::App* cmd, CliJobOptions& j, bool required);
/// The command as typed, each argument shell-quoted when it needs it (printed on generated pages).
std::string command_line(int argc, char** argv);

// One function per group, called by main in this order (the order of `actionshift --help`).
void register_core_commands(CLI::App& app, CliContext& ctx);      ///< validate, contract, splits, bench (cli_core.cpp)
void register_selftest_commands(CLI::App& app, CliContext& ctx);  ///< selftest, audit, record (cli_selftest.cpp)
void register_policy_commands(CLI::App& app, CliContext& ctx);    ///< train, gate0 (cli_policy.cpp)
void register_eval_commands(CLI::App& app, CliContext& ctx);      ///< run, plan, summarize, gates, compare, calibrate (cli_eval.cpp)
void register_render_commands(CLI::App& app, CliContext& ctx);    ///< render, montage, report (cli_render.cpp)

}  // namespace actionshift::cli
