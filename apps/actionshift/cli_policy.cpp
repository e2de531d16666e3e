// CLI11 registration of train bc | identifier | ppo and gate0 (cmd_policy.cpp, cmd_identifier.cpp
// implement them)
#include "cli_common.hpp"
#include "cmd_identifier.hpp"
#include "cmd_policy.hpp"

#include "actionshift/sim/env.hpp"

#include <iostream>

namespace actionshift::cli {

void register_policy_commands(CLI::App& app, CliContext& ctx) {
  // ---- train bc | gate0 (policy layer)
  auto* train = app.add_subcommand("train", "Train backbones and identifiers");
  train->require_subcommand(1);
  auto& train_o = ctx.make<cli::TrainBcOptions>();
  auto* bc = train->add_subcommand(
      "bc", "Train the MLP backbone of a task by DAgger from the scripted expert (Eigen, Adam; seeded and\n"
            "deterministic). Writes configs/backbones/<task>.mlp[-delay-aware].asmlp (docs/backbones.md).");
  bc->add_option("--task", train_o.task, "pick_cube, push_cube, pull_cube, stack_cube")->required();
  bc->add_option("--profile", train_o.train.profile, "Simulator fidelity profile of the rollouts: maniskill or ideal")->check(kProfile)
      ->capture_default_str();
  bc->add_flag("--delay-aware", train_o.train.delay_aware, "Append the last 4 actions to the input; train under random lag {0,1,2,4}");
  bc->add_option("--seed", train_o.train.seed, "Seed")->check(kSeed)->capture_default_str();
  bc->add_option("--iterations", train_o.train.iterations, "DAgger iterations (the first rolls out the expert)")->capture_default_str();
  bc->add_option("--episodes", train_o.train.episodes_per_iteration, "Episodes per iteration")->capture_default_str();
  bc->add_option("--steps", train_o.train.steps_per_iteration, "Adam steps per iteration")->capture_default_str();
  bc->add_option("--threads", train_o.train.threads, "Data-collection threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  bc->add_option("--hidden", train_o.hidden, "Hidden layer widths (tanh), comma-separated")->capture_default_str();
  bc->add_option("--out", train_o.out, "Weight file (default: configs/backbones/<task>.<backbone>.asmlp)");
  bc->add_option("--progress", train_o.progress, "auto, bar or lines (one line per iteration) or off, as for run")
      ->capture_default_str();
  bc->callback([&] { ctx.action = [&] { return cli::run_train_bc(train_o); }; });
  auto& tid_o = ctx.make<cli::TrainIdentifierCliOptions>();
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
  tid->callback([&] { ctx.action = [&] { return cli::run_train_identifier(tid_o); }; });
  auto& ppo_o = ctx.make<cli::TrainPpoOptions>();
  auto* ppo = train->add_subcommand(
      "ppo", "Train a PPO backbone of a task (clipped objective, GAE, Adam; Gaussian actor-critic MLPs on Eigen,\n"
             "vectorised rollouts over --envs environments on all cores, the normalized dense reward). Defaults: the\n"
             "ManiSkill PPO baseline's where they transfer (docs/backbones.md, PPO). Deterministic given the seed,\n"
             "whatever the thread count. Writes the actor mean as configs/backbones/<task>.ppo.asmlp (backbone\n"
             "`ppo`; checkpointed after every evaluation) and a training curve, one JSON line per iteration.");
  ppo->add_option("--task", ppo_o.task, ctx.task_list)->required();
  ppo->add_option("--profile", ppo_o.ppo.profile, "Simulator fidelity profile of the rollouts: maniskill or ideal")->check(kProfile)->capture_default_str();
  ppo->add_option("--seed", ppo_o.ppo.seed, "Seed (initialisation, episodes, exploration noise, minibatches)")->check(kSeed)->capture_default_str();
  ppo->add_option("--total-steps", ppo_o.ppo.total_steps, "Environment steps of the run")->capture_default_str();
  ppo->add_option("--envs", ppo_o.ppo.num_envs, "Parallel environments")->capture_default_str();
  ppo->add_option("--rollout-steps", ppo_o.ppo.num_steps, "Steps per environment per iteration")->capture_default_str();
  ppo->add_option("--minibatches", ppo_o.ppo.num_minibatches, "Minibatches per epoch")->capture_default_str();
  ppo->add_option("--epochs", ppo_o.ppo.update_epochs, "Epochs per update")->capture_default_str();
  ppo->add_option("--lr", ppo_o.ppo.learning_rate, "Adam learning rate")->capture_default_str();
  ppo->add_option("--gamma", ppo_o.ppo.gamma, "Discount")->capture_default_str();
  ppo->add_option("--gae-lambda", ppo_o.ppo.gae_lambda, "GAE lambda")->capture_default_str();
  ppo->add_option("--target-kl", ppo_o.ppo.target_kl, "Stop an update's epochs above this approximate KL (<= 0: never)")
      ->check(kNotNan)
      ->capture_default_str();
  ppo->add_option("--hidden", ppo_o.hidden, "Hidden layer widths of actor and critic, comma separated")->capture_default_str();
  ppo->add_option("--eval-every", ppo_o.ppo.eval_every, "Iterations between deterministic evaluations (and checkpoints)")->capture_default_str();
  ppo->add_option("--eval-episodes", ppo_o.ppo.eval_episodes, "Episodes per evaluation (training seed stream)")->capture_default_str();
  ppo->add_option("--threads", ppo_o.ppo.threads, "Worker threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  ppo->add_option("--out", ppo_o.out, "Weight file (default: configs/backbones/<task>.ppo.asmlp)");
  ppo->add_option("--curve", ppo_o.curve, "Training curve, JSON lines (default: the weight file's name with .curve.jsonl)");
  ppo->add_flag("--delay-aware", ppo_o.ppo.delay_aware,
                "Delay-aware PPO (the long-lag solve): the networks also see the last 4 executed actions and each\n"
                "training episode runs under a lag drawn from {0, 1, 2, 4}; writes <task>.ppo-delay-aware.asmlp");
  ppo->add_flag("--anneal-lr", ppo_o.ppo.anneal_lr, "Anneal the learning rate linearly to 0 over the run");
  ppo->add_option("--stop-after", ppo_o.ppo.stop_steps,
                  "End the run after this many environment steps (the learning-rate schedule still spans\n"
                  "--total-steps): how an annealed run's checkpoint is reproduced");
  ppo->add_flag("--terminal-success", ppo_o.terminal_success,
                "Treat a success as terminal (value 0 after it) instead of bootstrapping it with the critic, as\n"
                "ManiSkill's ppo.py does; the setting of earlier releases (rewards hovering short of the goal)");
  ppo->add_option("--init-from", ppo_o.init_from,
                  "Warm start (fine-tuning): the actor starts as this backbone file (same task and hidden widths; a\n"
                  "reactive file may start a --delay-aware run, its history inputs weighted 0); the critic starts fresh");
  ppo->add_option("--init-log-std", ppo_o.ppo.init_log_std, "Initial log standard deviation of the exploration noise")->capture_default_str();
  ppo->add_option("--critic-warmup", ppo_o.ppo.critic_warmup,
                  "Iterations at the start that train only the critic (actor frozen), for a warm start")->capture_default_str();
  ppo->add_option("--progress", ppo_o.progress, "auto, bar (one updating line), lines (one per iteration) or off")->capture_default_str();
  ppo->callback([&] { ctx.action = [&] { return cli::run_train_ppo(ppo_o); }; });
  auto& dp_o = ctx.make<cli::TrainDpCliOptions>();
  auto* dp = train->add_subcommand(
      "dp", "Train a Diffusion Policy backbone (conditional 1-D U-Net, DDPM; docs/backbones.md) on the scripted expert's\n"
            "demonstrations (Eigen, AdamW, EMA; seeded and deterministic). Writes FILE, used as --backbone dp:FILE.");
  dp->add_option("--task", dp_o.task, "pick_cube, push_cube, pull_cube, stack_cube")->required();
  dp->add_option("--out", dp_o.out, "Weight file (.asdp)")->required();
  dp->add_option("--profile", dp_o.dp.profile, "Simulator fidelity profile of the demonstrations")->check(kProfile)->capture_default_str();
  dp->add_option("--seed", dp_o.dp.seed, "Seed")->check(kSeed)->capture_default_str();
  dp->add_option("--demos", dp_o.dp.demos, "Expert episodes (only successful ones are kept)")->capture_default_str();
  dp->add_option("--iterations", dp_o.dp.iterations, "Optimiser steps")->capture_default_str();
  dp->add_option("--batch", dp_o.dp.batch_size, "Minibatch size")->capture_default_str();
  dp->add_option("--down-dims", dp_o.down_dims, "U-Net widths per level, comma-separated (the paper: 64,128,256)")->capture_default_str();
  dp->add_option("--ddim-steps", dp_o.dp.ddim_steps, "Sampler of the policy: 0 = DDPM over all 100 steps, else DDIM steps")->capture_default_str();
  dp->add_option("--lr", dp_o.dp.learn.learning_rate, "AdamW peak step size (500 warm-up steps, cosine decay)")->capture_default_str();
  dp->add_option("--threads", dp_o.dp.threads, "Threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  dp->add_option("--checkpoint", dp_o.dp.checkpoint,
                 "Checkpoint file: written every --checkpoint-every iterations; if it exists, training continues from\n"
                 "it (only a checkpoint of the same settings), so a killed run re-run with the same command ends with\n"
                 "the same bytes; removed once the weight file is written. Not part of the recorded command");
  dp->add_option("--checkpoint-every", dp_o.dp.checkpoint_every, "Iterations between checkpoints")
      ->check(CLI::Range(1, 1000000000))
      ->capture_default_str();
  dp->add_option("--progress", dp_o.progress, "auto, bar or lines (one line per 50 iterations) or off")->capture_default_str();
  dp->callback([&] { ctx.action = [&] { return cli::run_train_dp(dp_o); }; });
  auto& gate0_o = ctx.make<cli::Gate0Options>();
  auto* gate0 = app.add_subcommand(
      "gate0", "Gate 0 for a backbone: competence (success_once, Wilson 95 % interval vs the floor) and wrapper\n"
               "parity (identity-wrapped vs unwrapped, same initial states); decision advance or exclude (exit 1).\n"
               "Backbones: expert, expert-delay-aware, mlp, mlp-delay-aware, ppo, ppo-delay-aware, dp (the task's committed\n"
               "Diffusion Policy, configs/backbones/<task>.dp.asdp), mlp:<file>, dp:<file>, external:<command>.");
  gate0->add_option("--backbone", gate0_o.backbone, "Backbone")->capture_default_str();
  gate0->add_option("--task", gate0_o.task, "Task")->required();
  gate0->add_option("--profile", gate0_o.run.profile, "Simulator fidelity profile: maniskill or ideal (docs/sim.md)")->check(kProfile)
      ->capture_default_str();
  gate0->add_option("--episodes", gate0_o.run.episodes, "Episodes (each run unwrapped and identity-wrapped)")->capture_default_str();
  gate0->add_option("--seed", gate0_o.run.seed, "Experimental seed")->check(kSeed)->capture_default_str();
  gate0->add_option("--floor", gate0_o.run.floor, "Competence floor (default: 0.5, peg_insertion_side 0.2)")
      ->check(CLI::Range(0.0, 1.0) & kNotNan);
  gate0->add_option("--horizon", gate0_o.run.horizon,
                    "Control steps per episode (default 0: the task's, 50; peg_insertion_side 100). The reference\n"
                    "evaluates its Diffusion Policy at 100 on every task; the verdict records a horizon given here")
      ->check(CLI::Range(0, sim::kMaxHorizon))
      ->capture_default_str();
  gate0->add_option("--rule", gate0_o.rule, "Competence statistic: wilson_lower or point_estimate")->capture_default_str();
  gate0->add_option("--threads", gate0_o.run.threads, "Worker threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  gate0->add_flag("--json", gate0_o.json, "Print the verdict file instead of text");
  gate0->add_option("--out", gate0_o.out, "Write the verdict file here");
  gate0->add_option("--backbones-dir", gate0_o.backbones_dir, "Directory of the MLP weight files");
  gate0->add_option("--step-timeout", gate0_o.step_timeout_s, "Seconds an external policy may take per step")
      ->check(CLI::Range(0.001, 86400.0) & kNotNan)
      ->capture_default_str();
  gate0->add_option("--progress", gate0_o.progress,
                    "auto (a bar on a terminal, else lines), bar, lines or off, as for run")->capture_default_str();
  auto& gate0_quiet = ctx.make<bool>(false);
  gate0->add_flag("--quiet", gate0_quiet, "Same as --progress off");
  add_robot_options(gate0, gate0_o.robot);
  gate0->callback([&] {
    ctx.action = [&] {
      if (gate0_quiet) gate0_o.progress = "off";
      return cli::run_gate0(gate0_o);
    };
  });
}

}  // namespace actionshift::cli
