#pragma once
// Policy subcommands of the actionshift CLI as plain functions (no CLI11 here): cli_policy.cpp binds
// the options straight into these structs, whose library settings (policy::TrainBcOptions,
// policy::PpoOptions, policy::Gate0Run) are checked once, by the library's own check.
// Each returns 0 ok, 1 check failed (Gate 0 "exclude"), 2 bad input.

#include "commands.hpp"

#include "actionshift/policy/dp.hpp"
#include "actionshift/policy/gate0.hpp"
#include "actionshift/policy/ppo.hpp"
#include "actionshift/policy/train.hpp"

#include <cstdint>
#include <iostream>
#include <string>

namespace actionshift::cli {

// `actionshift train bc --task T [--delay-aware] [--seed S] [--iterations N] [--episodes N]
//  [--steps N] [--threads N] [--out FILE]`
struct TrainBcOptions {
  /// Bound directly: --profile, --delay-aware, --seed, --iterations, --episodes
  /// (episodes_per_iteration), --steps (steps_per_iteration), --threads. `task` and `hidden` are
  /// set from the text options below.
  policy::TrainBcOptions train;
  std::string task;                 // --task
  std::string out;                  // --out FILE ("" → configs/backbones/<task>.mlp[-delay-aware].asmlp)
  std::string progress{"auto"};     // --progress auto|bar|lines|off: one line per iteration unless off
  std::string hidden{"256,256"};    // --hidden: tanh hidden layer widths, comma-separated
};
int run_train_bc(TrainBcOptions options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift train ppo --task T [--seed S] [--total-steps N] [--envs N] [--rollout-steps N] ...
//  [--curve FILE] [--out FILE]`
struct TrainPpoOptions {
  /// Bound directly: --profile, --seed, --total-steps, --envs (num_envs), --rollout-steps (num_steps),
  /// --minibatches (num_minibatches), --epochs (update_epochs), --lr, --gamma, --gae-lambda,
  /// --target-kl, --eval-every, --eval-episodes, --threads, --delay-aware, --anneal-lr, --stop-after
  /// (stop_steps), --init-log-std, --critic-warmup. `task`, `hidden`, `bootstrap_success` and
  /// `init_actor` are set from the options below.
  policy::PpoOptions ppo;
  std::string task;                   // --task
  std::string hidden{"256,256,256"};  // --hidden widths, comma separated
  std::string out;                    // --out FILE ("" → configs/backbones/<task>.ppo.asmlp)
  std::string curve;                  // --curve FILE ("" → <out without .asmlp>.curve.jsonl)
  std::string progress{"auto"};       // --progress auto|bar|lines|off
  bool terminal_success{false};       // --terminal-success (value 0 after a success; earlier releases)
  std::string init_from;              // --init-from FILE: warm-start the actor from a backbone file
};
int run_train_ppo(TrainPpoOptions options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift train dp --task T --out FILE [--seed S] [--demos N] [--iterations N] [--batch N]
//  [--down-dims 32,64,128] [--ddim-steps N] [--lr X] [--threads N] [--progress M]`: a Diffusion Policy
// (policy/dp.hpp) from the scripted expert's demonstrations; the file is the backbone dp:FILE
struct TrainDpCliOptions {
  /// Bound directly: --profile, --seed, --demos, --iterations, --batch (batch_size), --ddim-steps,
  /// --lr (learn.learning_rate), --threads; checked once, by policy::check_train_dp_options. `task` and
  /// `down_dims` are set from the options below.
  policy::TrainDpOptions dp;
  std::string task;                    // --task
  std::string down_dims{"32,64,128"};  // --down-dims U-Net widths, comma separated
  std::string out;                     // --out FILE (.asdp)
  std::string progress{"auto"};        // --progress auto|bar|lines|off
};
int run_train_dp(const TrainDpCliOptions& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift gate0 --backbone B --task T --episodes N [--seed S] [--floor F] [--rule R]
//  [--threads N] [--json] [--out FILE] [--backbones-dir DIR] [--step-timeout S]`
struct Gate0Options {
  /// Bound directly: --profile, --episodes, --seed, --floor (< 0: the task's reference floor),
  /// --threads. `rule`, `robot` and `progress` are set from the options below.
  policy::Gate0Run run;
  std::string backbone{"expert"};   // --backbone
  std::string task;                 // --task
  std::string rule{"wilson_lower"}; // --rule wilson_lower|point_estimate
  bool json{false};                 // --json: print the verdict file instead of text
  std::string out;                  // --out FILE: write the verdict file
  std::string backbones_dir;        // --backbones-dir ("" → default)
  double step_timeout_s{10.0};      // --step-timeout (external policies)
  std::string progress{"auto"};     // --progress auto|bar|lines|off (as `run`; --quiet = off)
  RobotOptions robot;               // --robot/--package
};
int run_gate0(Gate0Options options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

}  // namespace actionshift::cli
