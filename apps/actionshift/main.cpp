// The actionshift command-line tool: a thin dispatcher. Each group of subcommands registers its
// CLI11 options, bound straight into the option structs of the functions that implement it
// (cli_*.cpp, over cmd_*.cpp; cli_common.hpp); main parses, then runs the chosen command's action.
// Exit codes: 0 ok, 1 a check/gate failed, 2 bad input or usage, 130 a job stopped by Ctrl-C or
// SIGTERM. One-line errors on stderr.
#include "cli_common.hpp"
#include "cmd_selftest.hpp"
#include "commands.hpp"

#include "actionshift/adapt/registry.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/eval/slurm.hpp"
#include "actionshift/sim/env.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iostream>
#include <string_view>
#include <vector>

using namespace actionshift;

namespace actionshift::cli {

// the command as typed, each argument shell-quoted when it needs it (printed on generated pages)
std::string command_line(int argc, char** argv) {
  std::string out = "actionshift";
  for (int i = 1; i < argc; ++i) {
    const std::string_view a(argv[i]);
    const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./:=@,+") ==
                                         std::string_view::npos;
    out += " " + (plain ? std::string(a) : eval::shell_quote(a));
  }
  return out;
}

// CLI11 parses "-1" into an unsigned option as 2**64 - 1 and saturates 2**64: seeds are checked as text
const CLI::Validator kSeed(
    [](std::string& s) -> std::string {
      const bool digits = !s.empty() && s.size() <= 20 && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
      if (digits && (s.size() < 20 || s <= "18446744073709551615")) return {};
      return "must be an integer in [0, 2**64) (got '" + s + "')";
    },
    "SEED");

// an empty value given on purpose ('' from a script's unset variable) is named as such, not read as
// "absent" (`contract hash ''` read stdin, `--task ''` said --task was missing) or as a nameless path
const CLI::Validator kNotEmpty([](std::string& s) { return s.empty() ? std::string("must not be empty") : std::string(); }, "");

// CLI::Range lets NaN through (every comparison with it is false)
const CLI::Validator kNotNan(
    [](std::string& s) -> std::string {
      const double v = std::strtod(s.c_str(), nullptr);
      return std::isnan(v) ? "must be a number (got '" + s + "')" : std::string();
    },
    "");

// every command that builds an environment names a fidelity profile: refused while parsing, as a
// usage error, rather than by whichever layer first builds a model
const CLI::Validator kProfile(
    [](std::string& s) -> std::string {
      if (kProfiles.find(s)) return {};
      return "unknown fidelity profile " + quote_input(s) + " (valid: " + kProfiles.list() + ")";
    },
    "PROFILE");

// --robot URDF [--package NAME=DIR]... on every command that builds an environment
// (`makes_jobs`: run and plan, whose job ids hash the description)
void add_robot_options(CLI::App* cmd, RobotOptions& r, bool makes_jobs) {
  cmd->add_option("--robot", r.urdf,
                  makes_jobs ? "Robot description (URDF; meshes through assimp) instead of the embedded Panda; its content hash\n"
                               "(URDF + collision meshes) enters the job id"
                             : "Robot description (URDF; meshes through assimp) instead of the embedded Panda: a 7-joint arm\n"
                               "to link panda_hand_tcp with finger joints panda_finger_joint1/2")
      ->check(CLI::Validator([](std::string& v) { return v.empty() ? std::string("must name a URDF file") : std::string(); }, ""));
  cmd->add_option("--package", r.packages, "NAME=DIR: resolve package://NAME/... in --robot (repeatable)");
}

}  // namespace actionshift::cli

namespace {

// CLI11 converts integers with strtoll/strtoull in base 0: 99999999999999999999 saturates to
// 2**63 - 1 (or 2**64 - 1) without an error, "010" is octal 8 and "0x10" is 16. Every integer option
// gets this check first: decimal digits (an optional sign) that fit 64 bits, rewritten without
// leading zeros so CLI11's own conversion reads them as decimal; CLI11 then checks the option's width.
CLI::Validator decimal_integer(bool is_unsigned) {
  return CLI::Validator(
      [is_unsigned](std::string& s) -> std::string {
        const std::string shown = quote_input(s);
        const char* p = s.data();
        const char* const end = s.data() + s.size();
        const bool negative = p != end && *p == '-';
        if (p != end && (*p == '+' || *p == '-')) ++p;
        const bool digits = p != end && std::all_of(p, end, [](char c) { return c >= '0' && c <= '9'; });
        if (is_unsigned) {
          std::uint64_t v = 0;
          if (!digits || negative || std::from_chars(p, end, v).ec != std::errc())
            return "must be an integer in [0, 2**64) (got " + shown + ")";
          s = std::to_string(v);
          return {};
        }
        if (!digits) return "expected a decimal integer (got " + shown + ")";
        std::uint64_t magnitude = 0;
        const std::uint64_t limit = negative ? std::uint64_t{1} << 63 : (std::uint64_t{1} << 63) - 1;
        if (std::from_chars(p, end, magnitude).ec != std::errc() || magnitude > limit)
          return "out of range: " + shown + " does not fit a 64-bit integer";
        s = (negative ? "-" : "") + std::to_string(magnitude);
        return {};
      },
      "");
}

// every integer option of `app` and its subcommands gets decimal_integer (run before parsing)
void check_integer_options(CLI::App* app) {
  for (CLI::Option* opt : app->get_options()) {
    const std::string type = opt->get_type_name();
    if (type.rfind("UINT", 0) == 0) opt->transform(decimal_integer(true));  // transform: runs first, may rewrite
    else if (type.rfind("INT", 0) == 0) opt->transform(decimal_integer(false));
  }
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; })) check_integer_options(sub);
}

// Levenshtein distance, for "did you mean" (command names are a few bytes)
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// CLI11 answers a misspelt command (`summarise`, `gate chek`) with "A subcommand is required":
// the words before the first option are walked through the command tree here, and the first that
// names no command is reported with the nearest command's name
std::string unknown_command(CLI::App& app, int argc, char** argv) {
  CLI::App* at = &app;
  std::string path = "actionshift";
  // `actionshift gate` (or `gate --results R`) without check/promote: name the commands it has
  const auto needs_command = [&]() -> std::string {
    const std::vector<CLI::App*> subs = at->get_subcommands([](CLI::App*) { return true; });
    if (at == &app || subs.empty()) return {};
    std::string names;
    for (const CLI::App* sub : subs) names += (names.empty() ? "" : ", ") + sub->get_name();
    return path + " needs a command: " + names;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string_view word = argv[i];
    if (word == "-h" || word == "--help" || word == "--version") return {};
    if (word.empty() || word.front() == '-') {
      for (int k = i + 1; k < argc; ++k)
        if (std::string_view(argv[k]) == "-h" || std::string_view(argv[k]) == "--help") return {};
      return needs_command();
    }
    const std::vector<CLI::App*> subs = at->get_subcommands([](CLI::App*) { return true; });
    if (subs.empty()) return {};  // a command's positional arguments
    CLI::App* next = nullptr;
    const CLI::App* nearest = nullptr;
    std::size_t best = 3;  // suggest only names within two edits
    for (CLI::App* sub : subs) {
      if (sub->get_name() == word) next = sub;
      const std::size_t d = edit_distance(word.substr(0, 64), sub->get_name());
      if (d < best) best = d, nearest = sub;
    }
    if (next == nullptr)
      return "unknown command " + quote_input(word) + " for " + path +
             (nearest ? " (did you mean '" + nearest->get_name() + "'?)" : std::string());
    at = next;
    path += " " + std::string(word);
  }
  return needs_command();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "ActionShift: a benchmark for hidden action-interface adaptation in robot manipulation.\n"
      "A frozen policy emits canonical actions; a hidden contract re-maps them before the robot's\n"
      "controller. This tool validates contracts and split manifests, runs evaluations and gates.",
      "actionshift"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("actionshift ") + ACTIONSHIFT_VERSION);
  app.footer("Exit codes: 0 ok, 1 a check or gate failed, 2 bad input or usage, 130 a job stopped by Ctrl-C or SIGTERM\n"
             "(re-run the same command to resume). selftest: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input.");
  cli::CliContext ctx;
  ctx.argc = argc;
  ctx.argv = argv;
  std::string& method_list = ctx.method_list;  // the registry's names, so the help cannot fall behind it
  for (const std::string& m : adapt::method_names()) method_list += (method_list.empty() ? "" : ", ") + m;
  std::string& task_list = ctx.task_list;  // the tasks' names, from their descriptions (sim/task.hpp)
  for (const sim::TaskId t : sim::all_tasks()) task_list += (task_list.empty() ? "" : ", ") + std::string(sim::task_name(t));
  cli::register_core_commands(app, ctx);
  cli::register_selftest_commands(app, ctx);
  cli::register_policy_commands(app, ctx);
  cli::register_eval_commands(app, ctx);
  cli::register_render_commands(app, ctx);

  if (const std::string unknown = unknown_command(app, argc, argv); !unknown.empty()) {
    std::cerr << "actionshift: error: " << unknown << " (see --help)\n";
    return cli::kBadInput;
  }
  check_integer_options(&app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::cerr << "actionshift: error: " << e.what() << " (see --help)\n";
    // selftest's bad-input exit code is 3 (2 means INCONCLUSIVE there)
    if (argc > 1 && std::string_view(argv[1]) == "selftest") return cli::kSelftestBadInput;
    return cli::kBadInput;
  }
  try {
    return ctx.action ? ctx.action() : cli::kBadInput;
  } catch (const eval::Interrupted& e) {  // Ctrl-C or SIGTERM during a job: its summary says where it stopped
    std::cerr << "actionshift: " << e.what() << "; re-run the same command to resume\n";
    return cli::kInterrupted;
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return cli::kBadInput;
  }
}
