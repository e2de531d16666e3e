// CLI11 registration of validate, contract, splits generate, bench env and bench adapt (cmd_core.cpp,
// cmd_bench_env.cpp, cmd_bench_adapt.cpp implement them)
#include "cli_common.hpp"
#include "cmd_bench_adapt.hpp"
#include "commands.hpp"

#include <iostream>

namespace actionshift::cli {

void register_core_commands(CLI::App& app, CliContext& ctx) {
  // ---- validate
  auto& validate_o = ctx.make<cli::ValidateOptions>();
  auto* validate = app.add_subcommand(
      "validate",
      "Validate split manifests and pools: recompute every hash, check grammar coverage, the split\n"
      "rules' disjointness and regeneration from (rule, seed); print one line per check and a summary.");
  validate->add_option("paths", validate_o.paths, "Manifest files or directories (default: the built-in manifests)")->check(kNotEmpty);
  validate->add_flag("-q,--quiet", validate_o.quiet, "Print only failed checks and the summary table");
  validate->add_flag("--json", validate_o.json, "Print one JSON report instead of text");
  validate->callback([&] { ctx.action = [&] { return cli::run_validate(validate_o); }; });

  // ---- contract hash | decode | encode
  auto* contract = app.add_subcommand("contract", "Contract utilities for scripting (JSON in, JSON out, one object per line)");
  contract->require_subcommand(1);
  auto& contract_o = ctx.make<cli::ContractOptions>();
  auto add_input = [&](CLI::App* c) {
    c->add_option("input", contract_o.input, "JSON text, a file of JSON lines, or - for stdin (default: stdin)")->check(kNotEmpty);
  };
  auto* hash = contract->add_subcommand(
      "hash", "Print {sha256, canonical, composition} for a contract object (bare or as {\"contract\": ...})");
  add_input(hash);
  hash->callback([&] { ctx.action = [&] { return cli::run_contract_hash(contract_o); }; });
  auto* dec = contract->add_subcommand(
      "decode",
      "Decode raw actions: {\"contract\": C, \"raw\": [7 numbers] | [[7], [7], ...], \"rotation\": 3x3 rows |\n"
      "\"quat_wxyz\": [4] (default identity), \"tracked_target\": [6] (default zeros)} -> {\"canonical\", ...}.\n"
      "A list of raw actions is decoded statefully (tracked target and lag FIFO from episode start).");
  add_input(dec);
  dec->callback([&] { ctx.action = [&] { return cli::run_contract_decode(contract_o); }; });
  auto* enc = contract->add_subcommand(
      "encode", "Encode a canonical action: {\"contract\", \"canonical\": [7], \"rotation\"|\"quat_wxyz\", \"tracked_target\"} -> {\"raw\"}");
  add_input(enc);
  enc->callback([&] { ctx.action = [&] { return cli::run_contract_encode(contract_o); }; });

  // ---- splits generate
  auto* splits = app.add_subcommand("splits", "Split and pool generation");
  splits->require_subcommand(1);
  auto& gen_o = ctx.make<cli::SplitsGenerateOptions>();
  auto* gen = splits->add_subcommand("generate", "Write the manifests of the seeded rules (docs/splits.md) to a directory");
  gen->add_option("--out", gen_o.out_dir, "Output directory")->capture_default_str();
  gen->add_option("--seed", gen_o.seed, "Generator seed")->check(kSeed)->capture_default_str();
  gen->add_option("--rule", gen_o.rules, "Only these rules (repeatable; default: all)");
  gen->callback([&] { ctx.action = [&] { return cli::run_splits_generate(gen_o); }; });

  // ---- bench env (sim layer)
  auto* bench = app.add_subcommand("bench", "Performance measurements");
  bench->require_subcommand(1);
  auto& bench_env_o = ctx.make<cli::BenchEnvOptions>();
  auto* bench_env = bench->add_subcommand(
      "env", "Control steps per second of the Bullet environment (scripted grasp-and-lift, with contact),\n"
             "on one thread and on all threads");
  bench_env->add_option("--task", bench_env_o.task, ctx.task_list)
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
  bench_env->callback([&] { ctx.action = [&] { return cli::run_bench_env(bench_env_o); }; });

  // ---- bench adapt (adapt layer)
  auto& bench_adapt_o = ctx.make<cli::BenchAdaptOptions>();
  auto* bench_adapt = bench->add_subcommand(
      "adapt", "Per-step cost of an adapter configuration on synthetic episodes: the true contract of each episode\n"
               "is a pool member, the response is the task's calibrated response model plus its noise, the TCP\n"
               "orientation turns slowly. Reports the first selection of an episode (from the uniform belief),\n"
               "encode on probe and on task steps, observe (the belief update) and the whole step, in microseconds\n"
               "(medians over repetitions, one thread). See docs/results/benchmarks.md.");
  bench_adapt->add_option("--method", bench_adapt_o.bench.method, "Adapter method (docs/adapters.md)")->capture_default_str();
  bench_adapt->add_option("--pool", bench_adapt_o.pool, "Declared pool: reference9, full or a pool manifest file (pool methods)")
      ->capture_default_str();
  bench_adapt->add_option("--params", bench_adapt_o.params, "Method parameters as a JSON object (defaults: docs/adapters.md)")
      ->capture_default_str();
  bench_adapt->add_option("--task", bench_adapt_o.task, "Task whose built-in response calibration is the response model")
      ->capture_default_str();
  bench_adapt->add_option("--profile", bench_adapt_o.profile, "Simulator fidelity profile of that calibration: maniskill or ideal")->check(kProfile)
      ->capture_default_str();
  bench_adapt->add_option("--episodes", bench_adapt_o.bench.episodes, "Episodes per repetition")->capture_default_str();
  bench_adapt->add_option("--steps", bench_adapt_o.bench.steps, "Control steps per episode")->capture_default_str();
  bench_adapt->add_option("--repetitions", bench_adapt_o.bench.repetitions, "Repetitions (the figures are their medians)")
      ->capture_default_str();
  bench_adapt->add_option("--seed", bench_adapt_o.bench.seed, "Seed of the synthetic episodes")->check(kSeed)->capture_default_str();
  bench_adapt->add_flag("--json", bench_adapt_o.json, "Print one JSON object");
  bench_adapt->callback([&] { ctx.action = [&] { return cli::run_bench_adapt(bench_adapt_o); }; });
}

}  // namespace actionshift::cli
