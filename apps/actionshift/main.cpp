// The actionshift command-line tool: the only translation unit that includes CLI11.
// Each subcommand fills an options struct and calls a plain function (commands.hpp).
// Exit codes: 0 ok, 1 a check/gate failed, 2 bad input or usage. One-line errors on stderr.
#include "cmd_policy.hpp"
#include "cmd_selftest.hpp"
#include "commands.hpp"

#include <CLI/CLI.hpp>

#include <exception>
#include <functional>
#include <iostream>
#include <string_view>

using namespace actionshift;

int main(int argc, char** argv) {
  CLI::App app{
      "ActionShift: a benchmark for hidden action-interface adaptation in robot manipulation.\n"
      "A frozen policy emits canonical actions; a hidden contract re-maps them before the robot's\n"
      "controller. This tool validates contracts and split manifests, runs evaluations and gates.",
      "actionshift"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("actionshift ") + ACTIONSHIFT_VERSION);
  app.footer("Exit codes: 0 ok, 1 a check or gate failed, 2 bad input or usage.");
  std::function<int()> action;

  // ---- validate
  cli::ValidateOptions validate_o;
  auto* validate = app.add_subcommand(
      "validate",
      "Validate split manifests and pools: recompute every hash, check grammar coverage, the split\n"
      "rules' disjointness and regeneration from (rule, seed); print one line per check and a summary.");
  validate->add_option("paths", validate_o.paths, "Manifest files or directories (default: the built-in manifests)");
  validate->add_flag("-q,--quiet", validate_o.quiet, "Print only failed checks and the summary table");
  validate->add_flag("--json", validate_o.json, "Print one JSON report instead of text");
  validate->callback([&] { action = [&] { return cli::run_validate(validate_o); }; });

  // ---- contract hash | decode | encode
  auto* contract = app.add_subcommand("contract", "Contract utilities for scripting (JSON in, JSON out, one object per line)");
  contract->require_subcommand(1);
  cli::ContractOptions contract_o;
  auto add_input = [&](CLI::App* c) {
    c->add_option("input", contract_o.input, "JSON text, a file of JSON lines, or - for stdin (default: stdin)");
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
  gen->add_option("--seed", gen_o.seed, "Generator seed")->capture_default_str();
  gen->add_option("--rule", gen_o.rules, "Only these rules (repeatable; default: all)");
  gen->callback([&] { action = [&] { return cli::run_splits_generate(gen_o); }; });

  // ---- bench env (sim layer)
  auto* bench = app.add_subcommand("bench", "Performance measurements");
  bench->require_subcommand(1);
  cli::BenchEnvOptions bench_env_o;
  auto* bench_env = bench->add_subcommand(
      "env", "Control steps per second of the Bullet environment (scripted grasp-and-lift, with contact),\n"
             "on one thread and on all threads");
  bench_env->add_option("--task", bench_env_o.task, "pick_cube, push_cube, pull_cube, stack_cube, peg_insertion_side")
      ->capture_default_str();
  bench_env->add_option("--steps", bench_env_o.steps, "Control steps per thread")->capture_default_str();
  bench_env->add_option("--threads", bench_env_o.threads, "Threads for the all-threads figure (0: all cores)")
      ->capture_default_str();
  bench_env->add_flag("--json", bench_env_o.json, "Print one JSON object");
  bench_env->callback([&] { action = [&] { return cli::run_bench_env(bench_env_o); }; });

  // ---- train bc | gate0 (policy layer)
  auto* train = app.add_subcommand("train", "Train backbones");
  train->require_subcommand(1);
  cli::TrainBcOptions train_o;
  auto* bc = train->add_subcommand(
      "bc", "Train the MLP backbone of a task by DAgger from the scripted expert (Eigen, Adam; seeded and\n"
            "deterministic). Writes configs/backbones/<task>.mlp[-delay-aware].asmlp (docs/backbones.md).");
  bc->add_option("--task", train_o.task, "pick_cube, push_cube, pull_cube, stack_cube")->required();
  bc->add_flag("--delay-aware", train_o.delay_aware, "Append the last 4 actions to the input; train under random lag {0,1,2,4}");
  bc->add_option("--seed", train_o.seed, "Seed")->capture_default_str();
  bc->add_option("--iterations", train_o.iterations, "DAgger iterations (the first rolls out the expert)")->capture_default_str();
  bc->add_option("--episodes", train_o.episodes, "Episodes per iteration")->capture_default_str();
  bc->add_option("--steps", train_o.steps, "Adam steps per iteration")->capture_default_str();
  bc->add_option("--threads", train_o.threads, "Data-collection threads (0: all cores)")->capture_default_str();
  bc->add_option("--out", train_o.out, "Weight file (default: configs/backbones/<task>.<backbone>.asmlp)");
  bc->callback([&] { action = [&] { return cli::run_train_bc(train_o); }; });
  cli::Gate0Options gate0_o;
  auto* gate0 = app.add_subcommand(
      "gate0", "Gate 0 for a backbone: competence (success_once, Wilson 95 % interval vs the floor) and wrapper\n"
               "parity (identity-wrapped vs unwrapped, same initial states); decision advance or exclude (exit 1).\n"
               "Backbones: expert, expert-delay-aware, mlp, mlp-delay-aware, mlp:<file>, external:<command>.");
  gate0->add_option("--backbone", gate0_o.backbone, "Backbone")->capture_default_str();
  gate0->add_option("--task", gate0_o.task, "Task")->required();
  gate0->add_option("--episodes", gate0_o.episodes, "Episodes (each run unwrapped and identity-wrapped)")->capture_default_str();
  gate0->add_option("--seed", gate0_o.seed, "Experimental seed")->capture_default_str();
  gate0->add_option("--floor", gate0_o.floor, "Competence floor (default: 0.5, peg_insertion_side 0.2)");
  gate0->add_option("--rule", gate0_o.rule, "Competence statistic: wilson_lower or point_estimate")->capture_default_str();
  gate0->add_option("--threads", gate0_o.threads, "Worker threads (0: all cores)")->capture_default_str();
  gate0->add_flag("--json", gate0_o.json, "Print the verdict file instead of text");
  gate0->add_option("--out", gate0_o.out, "Write the verdict file here");
  gate0->add_option("--backbones-dir", gate0_o.backbones_dir, "Directory of the MLP weight files");
  gate0->add_option("--step-timeout", gate0_o.step_timeout_s, "Seconds an external policy may take per step")->capture_default_str();
  gate0->add_flag("--progress,!--quiet", gate0_o.progress, "No progress on stderr");
  gate0->callback([&] { action = [&] { return cli::run_gate0(gate0_o); }; });

  // ---- selftest (plug-and-verify; its own exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input)
  cli::SelftestOptions st_o;
  auto* st = app.add_subcommand(
      "selftest",
      "Plug-and-verify self-test: probe with bounded pulses, identify the action wiring over a declared pool\n"
      "and answer PASS, MISMATCH (with the diff in words) or INCONCLUSIVE (abstain). Contract arguments: a\n"
      "library name, MANIFEST:INDEX (e.g. reference_seen:0), a file with contract JSON, or inline JSON.\n"
      "Exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input. See docs/selftest.md.");
  st->add_option("--task", st_o.task, "Task (with --sim: pick_cube, push_cube, pull_cube, stack_cube, peg_insertion_side)")
      ->capture_default_str();
  auto* st_demo = st->add_option("--demo", st_o.demo,
                                 "Synthetic demo wiring: identity, swapped-axes, sign-flip, miswired, scaled, reversed, lagged, unmodeled");
  st->add_option("--hidden-contract", st_o.hidden_contract, "The robot's true wiring (default: the expected contract)")
      ->excludes(st_demo);
  st->add_option("--expected", st_o.expected, "The wiring the policy assumes")->capture_default_str();
  st->add_flag("--sim", st_o.sim, "Probe the Bullet environment of --task instead of the synthetic stand-in");
  st->add_option("--calibration", st_o.calibration, "--sim: response calibration JSON (default: the task's built-in one)");
  st->add_option("--frame-rotation", st_o.frame_rotation, "--sim: live (TCP orientation) or identity")->capture_default_str();
  st->add_option("--pool", st_o.pools,
                 "Declared pool: library, a manifest name or file (repeatable; default library, with --sim library + reference9)");
  st->add_option("--strategy", st_o.strategy, "Probe strategy: fixed or entropy")->capture_default_str();
  st->add_option("--budget", st_o.budget, "Probe steps (default 6, also with --sim: docs/selftest.md)");
  st->add_option("--amplitude", st_o.amplitude, "Probe bound per pose channel, in (0, 1] (default 0.5)");
  st->add_option("--confidence-floor", st_o.confidence_floor, "Per-field confidence needed to resolve a field")
      ->capture_default_str();
  st->add_option("--misspec-ratio", st_o.misspec_ratio, "Abstain when the best fit exceeds this many times the noise")
      ->capture_default_str();
  st->add_option("--seed", st_o.seed, "Seed (synthetic noise; sim episode)")->capture_default_str();
  st->add_flag("--json", st_o.json, "Print one JSON object instead of the text report");
  st->callback([&] { action = [&] { return cli::run_selftest(st_o); }; });

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
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return cli::kBadInput;
  }
}
