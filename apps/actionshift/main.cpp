// The actionshift command-line tool: the only translation unit that includes CLI11.
// Each subcommand fills an options struct and calls a plain function (commands.hpp).
// Exit codes: 0 ok, 1 a check/gate failed, 2 bad input or usage, 130 a job stopped by Ctrl-C or
// SIGTERM. One-line errors on stderr.
#include "cmd_audit.hpp"
#include "cmd_bench_adapt.hpp"
#include "cmd_identifier.hpp"
#include "cmd_policy.hpp"
#include "cmd_render.hpp"
#include "cmd_run.hpp"
#include "cmd_selftest.hpp"
#include "commands.hpp"

#include "actionshift/adapt/registry.hpp"
#include "actionshift/eval/plan.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/sim/env.hpp"

#include <CLI/CLI.hpp>

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

namespace {

// the command as typed, each argument shell-quoted when it needs it (printed on generated pages)
std::string command_line(int argc, char** argv) {
  std::string out = "actionshift";
  for (int i = 1; i < argc; ++i) {
    const std::string_view a(argv[i]);
    const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./:=@,+") ==
                                         std::string_view::npos;
    out += " " + (plain ? std::string(a) : actionshift::eval::shell_quote(a));
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
  std::function<int()> action;
  // --robot URDF [--package NAME=DIR]... on every command that builds an environment
  // (`makes_jobs`: run and plan, whose job ids hash the description)
  const auto add_robot_options = [](CLI::App* cmd, cli::RobotOptions& r, bool makes_jobs = false) {
    cmd->add_option("--robot", r.urdf,
                    makes_jobs ? "Robot description (URDF; meshes through assimp) instead of the embedded Panda; its content hash\n"
                                 "(URDF + collision meshes) enters the job id"
                               : "Robot description (URDF; meshes through assimp) instead of the embedded Panda: a 7-joint arm\n"
                                 "to link panda_hand_tcp with finger joints panda_finger_joint1/2")
        ->check(CLI::Validator([](std::string& v) { return v.empty() ? std::string("must name a URDF file") : std::string(); }, ""));
    cmd->add_option("--package", r.packages, "NAME=DIR: resolve package://NAME/... in --robot (repeatable)");
  };

  // the options that name one job: `run` and `render` share them, so a render reaches the run's job id
  std::string method_list;  // the registry's names, so the help cannot fall behind it
  for (const std::string& m : adapt::method_names()) method_list += (method_list.empty() ? "" : ", ") + m;
  std::string task_list;  // the tasks' names, from their descriptions (sim/task.hpp)
  for (const sim::TaskId t : sim::all_tasks()) task_list += (task_list.empty() ? "" : ", ") + std::string(sim::task_name(t));
  const auto add_job_options = [&](CLI::App* cmd, cli::CliJobOptions& j, bool required) {
    auto* task = cmd->add_option("--task", j.request.task, task_list)->check(kNotEmpty);
    auto* split = cmd->add_option("--split", j.request.split, "Split manifest: a built-in name (seen, reference_seen, ...) or a file")
                      ->check(kNotEmpty);
    auto* method = cmd->add_option("--method", j.request.method.name,
                                   "Adapter method (docs/adapters.md): " + method_list +
                                       ". A bare name runs the paper's method; a variant is NAME{VARIANT} or NAME{KEY=VALUE,...} "
                                       "(quote it for the shell), e.g. 'entropy_probes{calibrated}'")
                       ->check(kNotEmpty);
    if (required) {
      task->required();
      split->required();
      method->required();
    }
    cmd->add_option("--params", j.method_params, "Method parameters as a JSON object (defaults: docs/adapters.md)")
        ->capture_default_str();
    auto* seed = cmd->add_option("--seed", j.request.seed, "Experimental seed")->check(kSeed)->capture_default_str();
    cmd->add_option("--seed-file", j.seed_file,
                    "Read the experimental seed from FILE (one integer) instead of --seed: an evaluator's undisclosed seed "
                    "stays off the command line, which any process on the machine can read (docs/formats.md §1)")
        ->excludes(seed);
    cmd->add_option("--episodes", j.request.episodes,
                    "Episodes, dealt in blocks over the split's contracts: each contract once per block, in a seeded order, "
                    "every contract of a block from the same initial state")
        ->capture_default_str();
    cmd->add_option("--backbone", j.request.backbone, "Frozen policy: expert, mlp, external:<command>, ...")
        ->capture_default_str();
    cmd->add_option("--pool", j.request.pool, "Declared pool for pool-belief methods: reference9, full or a file");
    cmd->add_option("--rotation-mode", j.request.rotation_mode, "Tool-frame rotation: live (TCP) or identity")
        ->capture_default_str();
    cmd->add_option("--profile", j.request.profile,
                    "Simulator fidelity profile: maniskill (one-step IK, PD drives with inertia, as ManiSkill) or\n"
                    "ideal (converged IK, first-order servo); part of the job id (docs/sim.md)")->check(kProfile)
        ->capture_default_str();
    cmd->add_option("--obs-noise", j.request.obs_noise,
                    "Observation (sensor) noise, OFF by default: sigma of Gaussian noise on the observed TCP pose, in\n"
                    "metres per position coordinate and radians per rotation-vector component (0..0.1), drawn per\n"
                    "episode; seen by policy and adapter alike; part of the job id when non-zero (docs/sim.md 6.1)")
        ->capture_default_str();
    cmd->add_option("--calibration", j.calibration,
                    "Response calibration file for a method that needs one, instead of the task's built-in one (e.g.\n"
                    "`calibrate --obs-noise S --out FILE`); its hash is the job's calibration_sha256");
    add_robot_options(cmd, j.robot, /*makes_jobs=*/true);
    cmd->add_option("--method-rung", j.method_rung,
                    "--method external:<command> only: the rung it claims, pool, grammar or none (what the runner hands it;\n"
                    "docs/methods.md)")
        ->capture_default_str();
    cmd->add_option("--method-version", j.method_version, "--method external:<command> only: its declared version (in the job id)")
        ->capture_default_str();
    cmd->add_option("--method-files", j.method_files,
                    "--method external:<command> only: its script, weights, configuration (their content enters the job id)");
    cmd->add_option("--policy-files", j.policy_files,
                    "Files of an external:<command> backbone (script, weights, config): their content hash enters the\n"
                    "job id, so editing the policy makes a new job instead of reusing old results");
  };

  // ---- validate
  cli::ValidateOptions validate_o;
  auto* validate = app.add_subcommand(
      "validate",
      "Validate split manifests and pools: recompute every hash, check grammar coverage, the split\n"
      "rules' disjointness and regeneration from (rule, seed); print one line per check and a summary.");
  validate->add_option("paths", validate_o.paths, "Manifest files or directories (default: the built-in manifests)")->check(kNotEmpty);
  validate->add_flag("-q,--quiet", validate_o.quiet, "Print only failed checks and the summary table");
  validate->add_flag("--json", validate_o.json, "Print one JSON report instead of text");
  validate->callback([&] { action = [&] { return cli::run_validate(validate_o); }; });

  // ---- contract hash | decode | encode
  auto* contract = app.add_subcommand("contract", "Contract utilities for scripting (JSON in, JSON out, one object per line)");
  contract->require_subcommand(1);
  cli::ContractOptions contract_o;
  auto add_input = [&](CLI::App* c) {
    c->add_option("input", contract_o.input, "JSON text, a file of JSON lines, or - for stdin (default: stdin)")->check(kNotEmpty);
  };
  auto* hash = contract->add_subcommand(
      "hash", "Print {sha256, canonical, composition} for a contract object (bare or as {\"contract\": ...})");
  add_input(hash);
  hash->callback([&] { action = [&] { return cli::run_contract_hash(contract_o); }; });
  auto* dec = contract->add_subcommand(
      "decode",
      "Decode raw actions: {\"contract\": C, \"raw\": [7 numbers] | [[7], [7], ...], \"rotation\": 3x3 rows |\n"
      "\"quat_wxyz\": [4] (default identity), \"tracked_target\": [6] (default zeros)} -> {\"canonical\", ...}.\n"
      "A list of raw actions is decoded statefully (tracked target and lag FIFO from episode start).");
  add_input(dec);
  dec->callback([&] { action = [&] { return cli::run_contract_decode(contract_o); }; });
  auto* enc = contract->add_subcommand(
      "encode", "Encode a canonical action: {\"contract\", \"canonical\": [7], \"rotation\"|\"quat_wxyz\", \"tracked_target\"} -> {\"raw\"}");
  add_input(enc);
  enc->callback([&] { action = [&] { return cli::run_contract_encode(contract_o); }; });

  // ---- splits generate
  auto* splits = app.add_subcommand("splits", "Split and pool generation");
  splits->require_subcommand(1);
  cli::SplitsGenerateOptions gen_o;
  auto* gen = splits->add_subcommand("generate", "Write the manifests of the seeded rules (docs/splits.md) to a directory");
  gen->add_option("--out", gen_o.out_dir, "Output directory")->capture_default_str();
  gen->add_option("--seed", gen_o.seed, "Generator seed")->check(kSeed)->capture_default_str();
  gen->add_option("--rule", gen_o.rules, "Only these rules (repeatable; default: all)");
  gen->callback([&] { action = [&] { return cli::run_splits_generate(gen_o); }; });

  // ---- bench env (sim layer)
  auto* bench = app.add_subcommand("bench", "Performance measurements");
  bench->require_subcommand(1);
  cli::BenchEnvOptions bench_env_o;
  auto* bench_env = bench->add_subcommand(
      "env", "Control steps per second of the Bullet environment (scripted grasp-and-lift, with contact),\n"
             "on one thread and on all threads");
  bench_env->add_option("--task", bench_env_o.task, task_list)
      ->capture_default_str();
  bench_env->add_option("--profile", bench_env_o.profile, "Simulator fidelity profile: maniskill or ideal")->check(kProfile)->capture_default_str();
  bench_env->add_option("--steps", bench_env_o.steps, "Control steps per thread")->capture_default_str();
  bench_env->add_option("--threads", bench_env_o.threads, "Threads for the all-threads figure (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  bench_env->add_flag("--json", bench_env_o.json, "Print one JSON object");
  bench_env->add_flag("--raw-bullet", bench_env_o.raw_bullet,
                      "Instead of throughput: time Env::step on one thread while recording what the controller hands\n"
                      "Bullet, then step the same rebuilt world with those inputs and no controller work (the raw-Bullet\n"
                      "limit); prints both per-step times, their ratio and whether the replay was bit-identical");
  add_robot_options(bench_env, bench_env_o.robot);
  bench_env->callback([&] { action = [&] { return cli::run_bench_env(bench_env_o); }; });

  // ---- bench adapt (adapt layer)
  cli::BenchAdaptOptions bench_adapt_o;
  auto* bench_adapt = bench->add_subcommand(
      "adapt", "Per-step cost of an adapter configuration on synthetic episodes: the true contract of each episode\n"
               "is a pool member, the response is the task's calibrated response model plus its noise, the TCP\n"
               "orientation turns slowly. Reports the first selection of an episode (from the uniform belief),\n"
               "encode on probe and on task steps, observe (the belief update) and the whole step, in microseconds\n"
               "(medians over repetitions, one thread). See docs/results/benchmarks.md.");
  bench_adapt->add_option("--method", bench_adapt_o.method, "Adapter method (docs/adapters.md)")->capture_default_str();
  bench_adapt->add_option("--pool", bench_adapt_o.pool, "Declared pool: reference9, full or a pool manifest file (pool methods)")
      ->capture_default_str();
  bench_adapt->add_option("--params", bench_adapt_o.params, "Method parameters as a JSON object (defaults: docs/adapters.md)")
      ->capture_default_str();
  bench_adapt->add_option("--task", bench_adapt_o.task, "Task whose built-in response calibration is the response model")
      ->capture_default_str();
  bench_adapt->add_option("--profile", bench_adapt_o.profile, "Simulator fidelity profile of that calibration: maniskill or ideal")->check(kProfile)
      ->capture_default_str();
  bench_adapt->add_option("--episodes", bench_adapt_o.episodes, "Episodes per repetition")->capture_default_str()->check(CLI::PositiveNumber);
  bench_adapt->add_option("--steps", bench_adapt_o.steps, "Control steps per episode")->capture_default_str()->check(CLI::PositiveNumber);
  bench_adapt->add_option("--repetitions", bench_adapt_o.repetitions, "Repetitions (the figures are their medians)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  bench_adapt->add_option("--seed", bench_adapt_o.seed, "Seed of the synthetic episodes")->check(kSeed)->capture_default_str();
  bench_adapt->add_flag("--json", bench_adapt_o.json, "Print one JSON object");
  bench_adapt->callback([&] { action = [&] { return cli::run_bench_adapt(bench_adapt_o); }; });

  // ---- selftest (plug-and-verify; its own exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input)
  cli::SelftestOptions st_o;
  auto* st = app.add_subcommand(
      "selftest",
      "Plug-and-verify self-test: probe with bounded pulses, identify the action wiring over a declared pool\n"
      "and answer PASS, MISMATCH (with the diff in words) or INCONCLUSIVE (abstain). Contract arguments: a\n"
      "library name, MANIFEST:INDEX (e.g. reference_seen:0), a file with contract JSON, or inline JSON.\n"
      "Exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input. See docs/selftest.md.");
  st->footer("Exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input or usage.");
  st->add_option("--task", st_o.task,
                 task_list + ": the environment probed with\n--sim, the report's task otherwise")
      ->capture_default_str();
  auto* st_demo = st->add_option("--demo", st_o.demo,
                                 "Synthetic demo wiring: identity, swapped-axes, sign-flip, miswired, scaled, reversed, lagged, unmodeled");
  st->add_option("--hidden-contract", st_o.hidden_contract, "The robot's true wiring (default: the expected contract)")
      ->excludes(st_demo);
  st->add_option("--expected", st_o.expected, "The wiring the policy assumes")->capture_default_str();
  st->add_flag("--sim", st_o.sim, "Probe the Bullet environment of --task instead of the synthetic stand-in");
  st->add_option("--profile", st_o.profile, "--sim: simulator fidelity profile: maniskill or ideal (docs/sim.md)")->check(kProfile)
      ->capture_default_str();
  st->add_option("--calibration", st_o.calibration, "--sim: response calibration JSON (default: the task's built-in one)");
  st->add_option("--frame-rotation", st_o.frame_rotation, "--sim: live (TCP orientation) or identity")->capture_default_str();
  st->add_option("--pool", st_o.pools,
                 "Declared pool: library, a manifest name or file (repeatable; default library, with --sim library + reference9)");
  st->add_option("--strategy", st_o.strategy, "Probe strategy: fixed or entropy")->capture_default_str();
  st->add_option("--budget", st_o.budget, "Probe steps (default 6, also with --sim: docs/selftest.md)");
  st->add_option("--amplitude", st_o.amplitude, "Probe bound per pose channel, in (0, 1] (default 0.5)");
  st->add_option("--confidence-floor", st_o.confidence_floor, "Per-field confidence needed to resolve a field")
      ->capture_default_str();
  st->add_option("--misspec-ratio", st_o.misspec_ratio,
                 "Abstain when the best fit exceeds this many times the noise (default 4; with --sim the task's value\n"
                 "calibrated on the simulator's own residuals, configs/selftest/sim_misspec.json)");
  st->add_option("--calibrate-misspec", st_o.calibrate_misspec,
                 "--sim: measure the misspecification threshold on the simulator (every pool member as the hidden\n"
                 "wiring, 8 seeds from --seed; max fit ratio of the correctly identified runs x 1.5) and write the\n"
                 "task's entry of this JSON file (configs/selftest/sim_misspec.json, embedded at build time)");
  st->add_option("--seed", st_o.seed, "Seed (synthetic noise; sim episode)")->check(kSeed)->capture_default_str();
  st->add_flag("--json", st_o.json, "Print one JSON object instead of the text report");
  add_robot_options(st, st_o.robot);
  st->callback([&] { action = [&] { return cli::run_selftest(st_o); }; });

  // ---- audit | record (issue 37: a recorded log's action contract, docs/audit.md)
  cli::AuditCliOptions audit_o;
  auto* audit = app.add_subcommand(
      "audit",
      "Audit a log: identify the action contract of recorded data (commanded actions + measured TCP poses) without\n"
      "probing. PASS, MISMATCH (the contract of the grammar that explains the log, in words) or INCONCLUSIVE\n"
      "(which fields the log does not excite, and what motion would decide). See docs/audit.md.");
  audit->footer("Exit codes: 0 PASS, 1 MISMATCH, 2 bad input or usage, 3 INCONCLUSIVE.");
  audit->add_option("log", audit_o.log, "The log: .csv, .jsonl, or .h5/.hdf5 (ManiSkill trajectory or robomimic layout)")
      ->required()->check(kNotEmpty);
  audit->add_option("--declared", audit_o.declared,
                    "The declared convention: a contract (library name, MANIFEST:INDEX, file or inline JSON) or a conventions\n"
                    "JSON {\"contract\": ..., \"rotation\": ..., \"gripper_range\": ..., \"action\": ...} (default: what the file\n"
                    "declares, e.g. ManiSkill's control_mode, else identity)");
  audit->add_option("--rotation", audit_o.rotation, "Declared rotation representation: axis_angle, euler_xyz or euler_zyx");
  audit->add_option("--gripper-range", audit_o.gripper_range, "Declared gripper range: -1..1 or 0..1");
  audit->add_option("--action-kind", audit_o.action_kind, "Declared meaning of the action: command, next_state or current_state");
  auto* audit_cal = audit->add_option("--calibration", audit_o.calibration, "Response calibration JSON (per-channel gain and noise)");
  audit->add_option("--task", audit_o.task, "Use this task's built-in calibration (pick_cube, ...)")->excludes(audit_cal);
  audit->add_option("--profile", audit_o.profile, "With --task: the simulator profile of the calibration")->check(kProfile)
      ->capture_default_str();
  audit->add_option("--confidence-floor", audit_o.confidence_floor, "Posterior mass a field needs to be resolved")->capture_default_str();
  audit->add_option("--misspec-ratio", audit_o.misspec_ratio, "Abstain when the best contract fits worse than this x the calibrated noise variance")
      ->capture_default_str();
  audit->add_option("--gain-tolerance", audit_o.gain_tolerance,
                    "Factor by which a log's response gain may differ from the calibrated one (scale is the set of grid\n"
                    "values within it)")->capture_default_str();
  audit->add_option("--max-steps", audit_o.max_steps, "Audit only the first N transitions");
  audit->add_flag("--json", audit_o.json, "Print one JSON object instead of the text report");
  audit->callback([&] { action = [&] { return cli::run_audit(audit_o); }; });

  cli::RecordOptions record_o;
  auto* record = app.add_subcommand(
      "record", "Write a log (actions, TCP poses, fingers) of one contract of a job from the simulator, for `audit` (docs/audit.md)");
  add_job_options(record, record_o.job, /*required=*/true);
  record->add_option("--contract", record_o.contract, "The split's contract to record (its episodes of the job)")->capture_default_str();
  record->add_option("--steps", record_o.steps, "Stop once this many transitions are logged");
  record->add_option("--out", record_o.out, "The log: .csv, .jsonl or .h5")->required()->check(kNotEmpty);
  record->add_option("--layout", record_o.layout, "For .h5: maniskill or robomimic")->capture_default_str();
  record->add_option("--truth", record_o.truth, "Write the recorded contract (conventions JSON) to this file");
  record->callback([&] { action = [&] { return cli::run_record(record_o); }; });

  // ---- train bc | gate0 (policy layer)
  auto* train = app.add_subcommand("train", "Train backbones and identifiers");
  train->require_subcommand(1);
  cli::TrainBcOptions train_o;
  auto* bc = train->add_subcommand(
      "bc", "Train the MLP backbone of a task by DAgger from the scripted expert (Eigen, Adam; seeded and\n"
            "deterministic). Writes configs/backbones/<task>.mlp[-delay-aware].asmlp (docs/backbones.md).");
  bc->add_option("--task", train_o.task, "pick_cube, push_cube, pull_cube, stack_cube")->required();
  bc->add_option("--profile", train_o.profile, "Simulator fidelity profile of the rollouts: maniskill or ideal")->check(kProfile)
      ->capture_default_str();
  bc->add_flag("--delay-aware", train_o.delay_aware, "Append the last 4 actions to the input; train under random lag {0,1,2,4}");
  bc->add_option("--seed", train_o.seed, "Seed")->check(kSeed)->capture_default_str();
  bc->add_option("--iterations", train_o.iterations, "DAgger iterations (the first rolls out the expert)")->capture_default_str();
  bc->add_option("--episodes", train_o.episodes, "Episodes per iteration")->capture_default_str();
  bc->add_option("--steps", train_o.steps, "Adam steps per iteration")->capture_default_str();
  bc->add_option("--threads", train_o.threads, "Data-collection threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  bc->add_option("--hidden", train_o.hidden, "Hidden layer widths (tanh), comma-separated")->capture_default_str();
  bc->add_option("--out", train_o.out, "Weight file (default: configs/backbones/<task>.<backbone>.asmlp)");
  bc->add_option("--progress", train_o.progress, "auto, bar or lines (one line per iteration) or off, as for run")
      ->capture_default_str();
  bc->callback([&] { action = [&] { return cli::run_train_bc(train_o); }; });
  cli::TrainIdentifierCliOptions tid_o;
  auto* tid = train->add_subcommand(
      "identifier", "Train a learned identifier of the unprivileged tier (docs/identifiers.md): softmax heads per contract\n"
                    "field over simulator rollouts under the identifier_training manifest's contracts (hash-disjoint from\n"
                    "every evaluation contract); seeded and deterministic. Prints the held-out field accuracy per horizon\n"
                    "and writes configs/identifiers/<task>.<kind>.asid (methods osi, probe_osi, recurrent_osi).");
  tid->add_option("--kind", tid_o.kind, "osi (passive window), probe_osi (6 fixed pulses first) or recurrent_osi (Elman cell)")
      ->required();
  tid->add_option("--task", tid_o.task, "Task of the rollouts")->capture_default_str();
  tid->add_option("--profile", tid_o.profile, "Simulator fidelity profile of the rollouts")->check(kProfile)->capture_default_str();
  tid->add_option("--seed", tid_o.seed, "Seed (weights init, rollouts, minibatches)")->check(kSeed)->capture_default_str();
  tid->add_option("--excitation", tid_o.excitation,
                  "expert: the scripted expert passed through (what a passive identifier sees); random: uniform raw\n"
                  "pose actions in [-0.5, 0.5] (the random-excitation ablation)")
      ->capture_default_str();
  tid->add_option("--episodes", tid_o.episodes, "Rollouts per training contract")->capture_default_str();
  tid->add_option("--train-steps", tid_o.train_steps, "Adam steps")->capture_default_str();
  tid->add_option("--max-contracts", tid_o.max_contracts, "Use only the first N training and held-out contracts (smoke runs; 0: all)")
      ->capture_default_str();
  tid->add_option("--threads", tid_o.threads, "Data-collection threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  tid->add_option("--out", tid_o.out, "Weight file (default: configs/identifiers/<task>.<kind>.asid)");
  tid->add_option("--verdicts", tid_o.verdicts, "Also write the held-out verdicts (field accuracy per horizon) as JSON here");
  tid->add_flag("--quiet", tid_o.quiet, "No progress lines");
  tid->callback([&] { action = [&] { return cli::run_train_identifier(tid_o); }; });
  cli::TrainPpoOptions ppo_o;
  auto* ppo = train->add_subcommand(
      "ppo", "Train a PPO backbone of a task (clipped objective, GAE, Adam; Gaussian actor-critic MLPs on Eigen,\n"
             "vectorised rollouts over --envs environments on all cores, the normalized dense reward). Defaults: the\n"
             "ManiSkill PPO baseline's where they transfer (docs/backbones.md, PPO). Deterministic given the seed,\n"
             "whatever the thread count. Writes the actor mean as configs/backbones/<task>.ppo.asmlp (backbone\n"
             "`ppo`; checkpointed after every evaluation) and a training curve, one JSON line per iteration.");
  ppo->add_option("--task", ppo_o.task, task_list)->required();
  ppo->add_option("--profile", ppo_o.profile, "Simulator fidelity profile of the rollouts: maniskill or ideal")->check(kProfile)->capture_default_str();
  ppo->add_option("--seed", ppo_o.seed, "Seed (initialisation, episodes, exploration noise, minibatches)")->check(kSeed)->capture_default_str();
  ppo->add_option("--total-steps", ppo_o.total_steps, "Environment steps of the run")->capture_default_str();
  ppo->add_option("--envs", ppo_o.envs, "Parallel environments")->capture_default_str();
  ppo->add_option("--rollout-steps", ppo_o.rollout_steps, "Steps per environment per iteration")->capture_default_str();
  ppo->add_option("--minibatches", ppo_o.minibatches, "Minibatches per epoch")->capture_default_str();
  ppo->add_option("--epochs", ppo_o.epochs, "Epochs per update")->capture_default_str();
  ppo->add_option("--lr", ppo_o.learning_rate, "Adam learning rate")->capture_default_str();
  ppo->add_option("--gamma", ppo_o.gamma, "Discount")->capture_default_str();
  ppo->add_option("--gae-lambda", ppo_o.gae_lambda, "GAE lambda")->capture_default_str();
  ppo->add_option("--target-kl", ppo_o.target_kl, "Stop an update's epochs above this approximate KL (<= 0: never)")
      ->check(kNotNan)
      ->capture_default_str();
  ppo->add_option("--hidden", ppo_o.hidden, "Hidden layer widths of actor and critic, comma separated")->capture_default_str();
  ppo->add_option("--eval-every", ppo_o.eval_every, "Iterations between deterministic evaluations (and checkpoints)")->capture_default_str();
  ppo->add_option("--eval-episodes", ppo_o.eval_episodes, "Episodes per evaluation (training seed stream)")->capture_default_str();
  ppo->add_option("--threads", ppo_o.threads, "Worker threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  ppo->add_option("--out", ppo_o.out, "Weight file (default: configs/backbones/<task>.ppo.asmlp)");
  ppo->add_option("--curve", ppo_o.curve, "Training curve, JSON lines (default: the weight file's name with .curve.jsonl)");
  ppo->add_flag("--delay-aware", ppo_o.delay_aware,
                "Delay-aware PPO (the long-lag solve): the networks also see the last 4 executed actions and each\n"
                "training episode runs under a lag drawn from {0, 1, 2, 4}; writes <task>.ppo-delay-aware.asmlp");
  ppo->add_flag("--anneal-lr", ppo_o.anneal_lr, "Anneal the learning rate linearly to 0 over the run");
  ppo->add_option("--stop-after", ppo_o.stop_after,
                  "End the run after this many environment steps (the learning-rate schedule still spans\n"
                  "--total-steps): how an annealed run's checkpoint is reproduced");
  ppo->add_flag("--terminal-success", ppo_o.terminal_success,
                "Treat a success as terminal (value 0 after it) instead of bootstrapping it with the critic, as\n"
                "ManiSkill's ppo.py does; the setting of earlier releases (rewards hovering short of the goal)");
  ppo->add_option("--init-from", ppo_o.init_from,
                  "Warm start (fine-tuning): the actor starts as this backbone file (same task and hidden widths; a\n"
                  "reactive file may start a --delay-aware run, its history inputs weighted 0); the critic starts fresh");
  ppo->add_option("--init-log-std", ppo_o.init_log_std, "Initial log standard deviation of the exploration noise")->capture_default_str();
  ppo->add_option("--critic-warmup", ppo_o.critic_warmup,
                  "Iterations at the start that train only the critic (actor frozen), for a warm start")->capture_default_str();
  ppo->add_option("--progress", ppo_o.progress, "auto, bar (one updating line), lines (one per iteration) or off")->capture_default_str();
  ppo->callback([&] { action = [&] { return cli::run_train_ppo(ppo_o); }; });
  cli::TrainDpCliOptions dp_o;
  auto* dp = train->add_subcommand(
      "dp", "Train a Diffusion Policy backbone (conditional 1-D U-Net, DDPM; docs/backbones.md) on the scripted expert's\n"
            "demonstrations (Eigen, AdamW, EMA; seeded and deterministic). Writes FILE, used as --backbone dp:FILE.");
  dp->add_option("--task", dp_o.task, "pick_cube, push_cube, pull_cube, stack_cube")->required();
  dp->add_option("--out", dp_o.out, "Weight file (.asdp)")->required();
  dp->add_option("--profile", dp_o.profile, "Simulator fidelity profile of the demonstrations")->check(kProfile)->capture_default_str();
  dp->add_option("--seed", dp_o.seed, "Seed")->check(kSeed)->capture_default_str();
  dp->add_option("--demos", dp_o.demos, "Expert episodes (only successful ones are kept)")->capture_default_str();
  dp->add_option("--iterations", dp_o.iterations, "Optimiser steps")->capture_default_str();
  dp->add_option("--batch", dp_o.batch, "Minibatch size")->capture_default_str();
  dp->add_option("--down-dims", dp_o.down_dims, "U-Net widths per level, comma-separated (the paper: 64,128,256)")->capture_default_str();
  dp->add_option("--ddim-steps", dp_o.ddim_steps, "Sampler of the policy: 0 = DDPM over all 100 steps, else DDIM steps")->capture_default_str();
  dp->add_option("--lr", dp_o.learning_rate, "AdamW peak step size (500 warm-up steps, cosine decay)")->capture_default_str();
  dp->add_option("--threads", dp_o.threads, "Threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  dp->add_option("--progress", dp_o.progress, "auto, bar or lines (one line per 50 iterations) or off")->capture_default_str();
  dp->callback([&] { action = [&] { return cli::run_train_dp(dp_o); }; });
  cli::Gate0Options gate0_o;
  auto* gate0 = app.add_subcommand(
      "gate0", "Gate 0 for a backbone: competence (success_once, Wilson 95 % interval vs the floor) and wrapper\n"
               "parity (identity-wrapped vs unwrapped, same initial states); decision advance or exclude (exit 1).\n"
               "Backbones: expert, expert-delay-aware, mlp, mlp-delay-aware, ppo, ppo-delay-aware, mlp:<file>, external:<command>.");
  gate0->add_option("--backbone", gate0_o.backbone, "Backbone")->capture_default_str();
  gate0->add_option("--task", gate0_o.task, "Task")->required();
  gate0->add_option("--profile", gate0_o.profile, "Simulator fidelity profile: maniskill or ideal (docs/sim.md)")->check(kProfile)
      ->capture_default_str();
  gate0->add_option("--episodes", gate0_o.episodes, "Episodes (each run unwrapped and identity-wrapped)")->capture_default_str();
  gate0->add_option("--seed", gate0_o.seed, "Experimental seed")->check(kSeed)->capture_default_str();
  gate0->add_option("--floor", gate0_o.floor, "Competence floor (default: 0.5, peg_insertion_side 0.2)")
      ->check(CLI::Range(0.0, 1.0) & kNotNan);
  gate0->add_option("--rule", gate0_o.rule, "Competence statistic: wilson_lower or point_estimate")->capture_default_str();
  gate0->add_option("--threads", gate0_o.threads, "Worker threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  gate0->add_flag("--json", gate0_o.json, "Print the verdict file instead of text");
  gate0->add_option("--out", gate0_o.out, "Write the verdict file here");
  gate0->add_option("--backbones-dir", gate0_o.backbones_dir, "Directory of the MLP weight files");
  gate0->add_option("--step-timeout", gate0_o.step_timeout_s, "Seconds an external policy may take per step")
      ->check(CLI::Range(0.001, 86400.0) & kNotNan)
      ->capture_default_str();
  gate0->add_option("--progress", gate0_o.progress,
                    "auto (a bar on a terminal, else lines), bar, lines or off, as for run")->capture_default_str();
  bool gate0_quiet = false;
  gate0->add_flag("--quiet", gate0_quiet, "Same as --progress off");
  add_robot_options(gate0, gate0_o.robot);
  gate0->callback([&] {
    action = [&] {
      if (gate0_quiet) gate0_o.progress = "off";
      return cli::run_gate0(gate0_o);
    };
  });

  // ---- run | plan | summarize | gate1 | gate check | calibrate (eval layer)
  cli::RunCliOptions run_o;
  std::int64_t run_job_index = -1;
  auto* run = app.add_subcommand(
      "run",
      "Run an evaluation job: episodes of a backbone under each contract of a split, through a method's\n"
      "adapter, written as one JSONL record per episode to <out>/<job id>.jsonl (+ .summary.json). The job\n"
      "id is the SHA-256 of everything that determines the episodes; a finished job is a no-op and a killed\n"
      "one resumes. Ctrl-C or SIGTERM stops it after the episodes already finished (exit 130; a second\n"
      "signal ends it at once). Either --task/--split/--method/--seed, or --plan FILE [--job-index I].");
  add_job_options(run, run_o.job, /*required=*/false);
  run->add_option("--plan", run_o.run.plan_file, "Run the jobs of a plan file (actionshift plan) instead")->check(kNotEmpty);
  auto* job_index = run->add_option("--job-index", run_job_index, "With --plan: only this job (a Slurm array task id)")
      ->check(CLI::Validator(
          [](std::string& v) { return !v.empty() && v[0] == '-' ? "must be a job index >= 0 (got " + v + ")" : std::string(); }, ""));
  run->add_option("--out", run_o.run.out_dir, "Results directory")->capture_default_str();
  run->add_option("--threads", run_o.run.threads, "Worker threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  run->add_flag("--fsync", run_o.run.fsync, "fsync after every record");
  run->add_option("--progress", run_o.run.progress, "auto, bar, lines or off")->capture_default_str();
  run->add_option("--step-timeout", run_o.run.step_timeout_s,
                  "Seconds an external:<command> backbone may take to read one request and to reply to it\n"
                  "(a process that overruns, floods replies or dies ends the job with an error)")
      ->check(CLI::Range(0.001, 86400.0) & kNotNan)
      ->capture_default_str();
  run->add_option("--sandbox", run_o.run.sandbox,
                  "auto, on or off: external:<command> backbones and methods run in new user, mount and PID\n"
                  "namespaces where they see no process of the runner's and find --out, --plan and --seed-file\n"
                  "empty (auto: when this machine allows it, else with a warning; on: or fail)")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  run->callback([&] {
    action = [&] {
      if (job_index->count() > 0 && run_o.run.plan_file.empty()) {  // was ignored: the single job ran
        std::cerr << "actionshift: error: --job-index: only applies with --plan (see --help)\n";
        return static_cast<int>(cli::kBadInput);
      }
      if (run_job_index >= 0) run_o.run.job_index = run_job_index;
      if (run_o.run.plan_file.empty() &&
          (run_o.job.request.task.empty() || run_o.job.request.split.empty() || run_o.job.request.method.name.empty())) {
        std::cerr << "actionshift: error: run needs --task, --split and --method, or --plan (see --help)\n";
        return static_cast<int>(cli::kBadInput);
      }
      return cli::run_run(run_o);
    };
  });

  cli::PlanOptions plan_o;
  auto* plan = app.add_subcommand(
      "plan", "Expand an experiment (configs/experiments/<name>.yaml) into its job list. --slurm also writes, beside\n"
              "the plan, <name>.sbatch (one array task per job: `actionshift run --plan ... --job-index`), <name>.merge.sbatch\n"
              "(summarize, and gate1 when the plan has oracle and no_adapt) and <name>.submit.sh, which submits the arrays in\n"
              "chunks under the cluster's MaxArraySize and the merge job with --dependency=afterok. Every path in them is\n"
              "absolute, so `bash <name>.submit.sh` works from any directory.");
  plan->add_option("--experiment", plan_o.experiment_file, "Experiment YAML")->required()->check(kNotEmpty);
  plan->add_option("--out", plan_o.out_dir, "Results directory of the jobs")->capture_default_str();
  plan->add_option("--plan", plan_o.plan_file, "Plan file (default <out>/<experiment>.plan.json)");
  plan->add_flag("--slurm", plan_o.slurm, "Also write a Slurm array script");
  plan->add_option("--slurm-script", plan_o.slurm_file, "Script path (default <out>/<experiment>.sbatch)");
  plan->add_option("--executable", plan_o.executable,
                   "The actionshift binary the array tasks call (default: this binary; a bare name is looked up on PATH;\n"
                   "written as an absolute path)");
  plan->add_option("--cpus-per-task", plan_o.cpus_per_task, "Slurm --cpus-per-task (also the tasks' --threads)")->capture_default_str();
  plan->add_option("--time", plan_o.time_limit, "Slurm --time per array task: M, M:S, H:M:S, D-H, D-H:M, D-H:M:S or UNLIMITED")
      ->capture_default_str();
  plan->add_option("--mem", plan_o.mem, "Slurm --mem per array task, e.g. 4G (default: the cluster's)");
  plan->add_option("--partition", plan_o.partition, "Slurm --partition");
  plan->add_option("--max-parallel", plan_o.max_parallel, "Array throttle (%N)");
  plan->add_option("--max-array-size", plan_o.max_array_size,
                   "Tasks per array (default: MaxArraySize from `scontrol show config`, else Slurm's default 1001)");
  cli::RobotOptions plan_robot;
  add_robot_options(plan, plan_robot, /*makes_jobs=*/true);
  std::vector<std::string> plan_policy_files;
  plan->add_option("--policy-files", plan_policy_files,
                   "Files of an external:<command> backbone (script, weights); their content hash enters every job id");
  plan->callback([&] { action = [&] { return cli::run_plan_cli(plan_o, plan_robot, plan_policy_files); }; });

  cli::SummarizeOptions sum_o;
  auto* summarize = app.add_subcommand("summarize", "Merge every <id>.jsonl in a directory into per-cell tables (Markdown or JSON)");
  summarize->add_option("dir", sum_o.results_dir, "Results directory")->required()->check(kNotEmpty);
  summarize->add_flag("--json", sum_o.json, "Print JSON instead of Markdown");
  summarize->add_option("--out", sum_o.out_file, "Also write the JSON summary to this file");
  summarize->callback([&] { action = [&] { return cli::run_summarize(sum_o); }; });

  cli::Gate1Options g1_o;
  auto* gate1 = app.add_subcommand(
      "gate1", "Gate 1 (privileged ceiling vs no adaptation): per task and split, oracle and no_adapt success with\n"
               "Wilson intervals and their paired bootstrap difference; writes a verdict file; exit 1 if a gated cell fails.");
  gate1->add_option("--results", g1_o.results_dir, "Results directory")->required();
  gate1->add_flag("--json", g1_o.json, "Print JSON");
  gate1->add_option("--verdict", g1_o.verdict_file, "Verdict file (default <results>/gate1.verdict.json)");
  gate1->add_option("--samples", g1_o.samples, "Bootstrap resamples")->check(CLI::Range(1, 1000000))->capture_default_str();
  gate1->add_option("--bootstrap-seed", g1_o.bootstrap_seed, "Bootstrap seed")->check(kSeed)->capture_default_str();
  gate1->callback([&] { action = [&] { return cli::run_gate1(g1_o); }; });

  auto* gate = app.add_subcommand("gate", "Compare gate verdicts with committed expectations (CI)");
  gate->require_subcommand(1);
  cli::GateCheckOptions gc_o;
  auto* gate_check = gate->add_subcommand(
      "check", "Recompute verdicts from --results (or read --actual) and exit 1 if an expected pass regressed");
  gate_check->add_option("--expected", gc_o.expected_file, "Committed verdict file")->required();
  gate_check->add_option("--results", gc_o.results_dir, "Results directory to recompute from");
  gate_check->add_option("--actual", gc_o.actual_file, "A verdict file to compare instead");
  gate_check->callback([&] { action = [&] { return cli::run_gate_check(gc_o); }; });
  cli::GatePromoteOptions gp_o;
  auto* gate_promote = gate->add_subcommand(
      "promote", "Promotion gate (docs/reference.md, section Gates): a candidate method vs its matched baseline per task and split: >= 5 points\n"
                 "(paired 95 % bootstrap interval above 0) or a success-vs-probe-cost Pareto point, without a safety\n"
                 "regression; a one-seed result under 0.3 is never promoted; < 3 matched seeds: extend_seeds.");
  gate_promote->add_option("--candidate", gp_o.candidate, "Candidate method")->required();
  gate_promote->add_option("--baseline", gp_o.baseline, "Matched baseline method")->required();
  gate_promote->add_option("--results", gp_o.results_dir, "Results directory")->required();
  gate_promote->add_flag("--json", gp_o.json, "Print the verdict file");
  gate_promote->add_option("--verdict", gp_o.verdict_file, "Verdict file (default <results>/promotion.<c>.vs.<b>.json)");
  gate_promote->callback([&] { action = [&] { return cli::run_gate_promote(gp_o); }; });

  cli::CompareOptions cmp_o;
  auto* compare = app.add_subcommand(
      "compare",
      "Everything a results page needs, as one JSON document (docs/formats.md, Comparison): per cell (task, split,\n"
      "method label, backbone) success with its Wilson 95 % interval, per-seed rates, probe steps and displacement,\n"
      "safety-flag rates and the paper's number; per --pair and (task, split, backbone) holding both labels the\n"
      "paired bootstrap difference (10000 resamples, seed 20260718), per-seed differences, the paper's difference\n"
      "with its significance, whether the signs agree, and the promotion verdict with the rule that decided.\n"
      "Cells whose episodes do not pair exactly are an error. Method labels are opaque and may hold '{', ',' and\n"
      "'=' (e.g. entropy_probes{calibrated}); only a label without a {...} suffix gets the paper's numbers.");
  compare->add_option("results", cmp_o.results_dirs, "Results directories (their records are merged)")->required();
  compare->add_option("--pair", cmp_o.pairs,
                      "A comparison 'CANDIDATE vs BASELINE' (one argument, quoted; the separator is ' vs ' with its\n"
                      "spaces, so labels may hold any other character); repeatable");
  compare->add_option("--pairs-from", cmp_o.pairs_file,
                      "A file of pairs: one 'CANDIDATE vs BASELINE' per line; blank lines and # comments ignored");
  compare->add_option("--paper", cmp_o.paper_file,
                      "Paper-numbers file (default: configs/paper/numbers.json as compiled into this build)");
  compare->add_option("--out", cmp_o.out_file, "Write the JSON here (default: stdout)");
  compare->add_flag("--common-episodes", cmp_o.common_episodes,
                    "Pair only the episodes both cells of a pair hold (a 50-episode job with the first 50 of a\n"
                    "200-episode one) instead of refusing cells whose episode sets differ; each comparison says in\n"
                    "'unpaired' how many it left out. Check those counts: an unfinished job is left out silently otherwise");
  compare->add_flag("--across-backbones", cmp_o.across_backbones,
                    "Backbone as a random effect: for each same-backbone pair and each (task, split) that two or\n"
                    "more backbones hold, add to 'across_backbones' the difference per backbone (cluster bootstrap\n"
                    "over seed and block, a block being the episodes that share an initial state), pooled over the\n"
                    "backbones (hierarchical bootstrap: backbones, then seeds, then blocks) and a verdict:\n"
                    "holds_on_every_backbone, holds_on_average, depends_on_backbone or not_shown");
  compare->callback([&] { action = [&] { return cli::run_compare(cmp_o); }; });

  cli::CalibrateOptions cal_o;
  auto* calibrate = app.add_subcommand(
      "calibrate", "Measure each pose channel's response gain, noise and R^2 on the unwrapped environment with\n"
                   "random actions (the likelihood of the belief adapters); prints the table, --out writes the JSON.");
  calibrate->add_option("--task", cal_o.task, "Task")->required();
  calibrate->add_option("--profile", cal_o.profile, "Simulator fidelity profile: maniskill or ideal")->check(kProfile)->capture_default_str();
  calibrate->add_option("--protocol", cal_o.protocol,
                        "maniskill_walk (the public reference implementation's, as it runs in ManiSkill: 8 random\n"
                        "walks of 64 steps, truncated and reset at the task's 50-step horizon as ManiSkill's vector\n"
                        "wrapper does, 63 samples each), reference_walk (the same walks without the reset) or\n"
                        "episodes (task episodes with resets, capped at the horizon)")
      ->capture_default_str();
  calibrate->add_option("--episodes", cal_o.episodes, "Random walks (maniskill_walk, reference_walk) or episodes; 1 to 100000")->check(CLI::Range(1, 100000))->capture_default_str();
  calibrate->add_option("--steps", cal_o.steps, "Steps per walk or episode (at least 2: a response needs two poses)")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000000));
  calibrate->add_option("--ik", cal_o.ik, "Ablation: override the profile's IK: single_step or converged");
  calibrate->add_option("--drive", cal_o.drive, "Ablation: override the arm drive: implicit_pd or velocity_servo");
  calibrate->add_option("--solver-iterations", cal_o.solver_iterations,
                        "Ablation: Bullet solver iterations per step, 1..1000 (default: the profile's, 15)");
  calibrate->add_option("--joint-limits", cal_o.joint_limits, "Ablation: arm joint limit constraints on or off");
  calibrate->add_option("--seed", cal_o.seed, "Seed")->check(kSeed)->capture_default_str();
  calibrate->add_option("--obs-noise", cal_o.obs_noise,
                        "Measure under observation noise of this sigma (as run --obs-noise; off by default); the\n"
                        "calibration's profile label gets [obs_noise=S]")
      ->capture_default_str();
  calibrate->add_option("--out", cal_o.out, "Write the calibration JSON here (e.g. configs/calibration/<profile>/<task>.json)");
  calibrate->add_flag("--json", cal_o.json, "Print the calibration JSON");
  add_robot_options(calibrate, cal_o.robot);
  calibrate->add_flag("--gripper-channel", cal_o.gripper_channel,
                      "Also fit the finger channel (gripper action vs mean finger-position change per step), which\n"
                      "grammar_belief uses with {\"gripper_channel\":true}; adds the optional \"gripper\" key");
  calibrate->callback([&] { action = [&] { return cli::run_calibrate(cal_o); }; });

  // ---- render | montage | report (render layer)
  cli::RenderOptions render_o;
  auto* render = app.add_subcommand(
      "render",
      "Render one episode of a job headless (OSMesa) exactly as `run` runs it: same job id, contract, episode\n"
      "seed, initial state and outcome as that episode's JSONL record, which is printed as one JSON line.\n"
      "Writes an animated GIF (every step) or a PNG (one frame) with an overlay of the step, the phase\n"
      "(reset / probe / act) and success. Episode E of contract I is the one of block E (the job's episodes\n"
      "E * contracts ... E * contracts + contracts - 1, in a seeded order) that runs contract I.");
  add_job_options(render, render_o.job, /*required=*/true);
  render->add_option("--step-timeout", render_o.step_timeout_s, "Seconds an external:<command> backbone may take per step (as for run)")
      ->check(CLI::Range(0.001, 86400.0) & kNotNan)
      ->capture_default_str();
  render->add_option("--contract", render_o.contract, "Contract index in the split")->capture_default_str();
  render->add_option("--episode", render_o.episode, "The contract's episode (0 = its first)")->capture_default_str();
  render->add_option("--camera", render_o.camera,
                     "default (the task's, like ManiSkill's human-render camera), front, side, top, or\n"
                     "EX,EY,EZ,TX,TY,TZ[,FOV_DEG] (eye, target [m], vertical field of view)")
      ->capture_default_str();
  render->add_option("--size", render_o.size, "Image size WIDTHxHEIGHT")->capture_default_str();
  render->add_option("--frame", render_o.frame, "PNG only: the state after this many steps (-1: the last)")->capture_default_str();
  render->add_option("--delay", render_o.delay_cs, "GIF: hundredths of a second per frame")->capture_default_str();
  render->add_flag("--clean", render_o.clean, "Same episode seed with the identity contract (the clean reference panel)");
  render->add_option("--label", render_o.label, "Overlay title (default: the method, or clean)");
  render->add_flag("--no-overlay", render_o.no_overlay, "No overlay");
  render->add_option("--out", render_o.out, "Output FILE.gif or FILE.png")->required();
  render->callback([&] { action = [&] { return cli::run_render(render_o); }; });

  cli::MontageOptions montage_o;
  auto* montage = app.add_subcommand(
      "montage", "Place GIF renders side by side (shorter ones hold their last frame): an animated GIF, or one\n"
                 "frame as PNG (e.g. the clean / no_adapt / adapted triptych).");
  montage->add_option("inputs", montage_o.inputs, "Input GIF files, left to right")->required();
  montage->add_option("--out", montage_o.out, "Output FILE.gif or FILE.png")->required();
  montage->add_option("--frame", montage_o.frame, "PNG only: frame index (-1: the last)")->capture_default_str();
  montage->add_option("--delay", montage_o.delay_cs, "GIF: hundredths of a second per frame")->capture_default_str();
  montage->callback([&] { action = [&] { return cli::run_montage(montage_o); }; });

  cli::ReportOptions report_o;
  auto* report = app.add_subcommand(
      "report", "Write a self-contained HTML page (index.html) and Markdown (report.md) for a results directory:\n"
                "the results summary table, gate verdicts, SVG figures (Gate 1, adaptation ladders, probe-cost\n"
                "Pareto, long lag; a figure whose inputs are absent is skipped) and the provenance of every number.");
  report->add_option("results", report_o.results_dirs,
                     "Results directory (with --leaderboard: one or more, merged as `compare` merges them)")->required();
  report->add_option("--out", report_o.out_dir, "Output directory")->required();
  report->add_flag("--leaderboard", report_o.leaderboard,
                   "Write the leaderboard instead (leaderboard.md, .html, .json): every method label against\n"
                   "--reference on each (task, split, backbone) where both ran: success with its Wilson interval,\n"
                   "the paired bootstrap difference and the promotion verdict; a method of your own is one more row");
  report->add_option("--reference", report_o.reference, "--leaderboard: the method every row is compared with")
      ->capture_default_str();
  report->add_option("--splits", report_o.splits, "--leaderboard: only these splits' cells (default: every split)")
      ->delimiter(',');
  report->add_flag("--common-episodes", report_o.common_episodes,
                   "--leaderboard: pair only the episodes both cells hold (as `compare --common-episodes`)");
  report->callback([&] {
    report_o.command = command_line(argc, argv);
    action = [&] { return cli::run_report(report_o); };
  });

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
    return action ? action() : cli::kBadInput;
  } catch (const eval::Interrupted& e) {  // Ctrl-C or SIGTERM during a job: its summary says where it stopped
    std::cerr << "actionshift: " << e.what() << "; re-run the same command to resume\n";
    return cli::kInterrupted;
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return cli::kBadInput;
  }
}
