#pragma once
// Policy subcommands of the actionshift CLI as plain functions (no CLI11 here): main.cpp maps parsed
// options onto these structs. Each returns 0 ok, 1 check failed (Gate 0 "exclude"), 2 bad input.

#include "commands.hpp"

#include <cstdint>
#include <iostream>
#include <string>

namespace actionshift::cli {

// `actionshift train bc --task T [--delay-aware] [--seed S] [--iterations N] [--episodes N]
//  [--steps N] [--threads N] [--out FILE]`
struct TrainBcOptions {
  std::string task;                 // --task
  std::string profile{"maniskill"}; // --profile
  bool delay_aware{false};          // --delay-aware: history of 4 actions, random lag {0,1,2,4}
  std::uint64_t seed{20260718};     // --seed
  int iterations{8};                // --iterations (DAgger iterations, the first is the expert's)
  int episodes{64};                 // --episodes per iteration
  int steps{1500};                  // --steps Adam steps per iteration
  unsigned threads{0};              // --threads for data collection (0: all cores)
  std::string out;                  // --out FILE ("" → configs/backbones/<task>.mlp[-delay-aware].asmlp)
  std::string progress{"auto"};     // --progress auto|bar|lines|off: one line per iteration unless off
  std::string hidden{"256,256"};    // --hidden: tanh hidden layer widths, comma-separated
};
int run_train_bc(const TrainBcOptions& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift train ppo --task T [--seed S] [--total-steps N] [--envs N] [--rollout-steps N] ...
//  [--curve FILE] [--out FILE]`
struct TrainPpoOptions {
  std::string task;                 // --task
  std::string profile{"maniskill"}; // --profile
  std::uint64_t seed{20260718};     // --seed
  std::int64_t total_steps{1'000'000};  // --total-steps (environment steps)
  int envs{64};                     // --envs parallel environments
  int rollout_steps{16};            // --rollout-steps per environment per iteration
  int minibatches{2};               // --minibatches per epoch
  int epochs{4};                    // --epochs per update
  double learning_rate{3e-4};       // --lr
  double gamma{0.8};                // --gamma
  double gae_lambda{0.9};           // --gae-lambda
  double target_kl{0.1};            // --target-kl (<= 0: off)
  std::string hidden{"256,256,256"};  // --hidden widths, comma separated
  int eval_every{10};               // --eval-every iterations
  int eval_episodes{32};            // --eval-episodes
  unsigned threads{0};              // --threads (0: all cores)
  std::string out;                  // --out FILE ("" → configs/backbones/<task>.ppo.asmlp)
  std::string curve;                // --curve FILE ("" → <out without .asmlp>.curve.jsonl)
  std::string progress{"auto"};     // --progress auto|bar|lines|off
  bool delay_aware{false};          // --delay-aware (observation ++ last 4 actions, lags {0,1,2,4})
  bool anneal_lr{false};             // --anneal-lr (linear to 0, ManiSkill ppo.py's anneal_lr)
  bool terminal_success{false};      // --terminal-success (value 0 after a success; earlier releases)
  std::int64_t stop_after{0};        // --stop-after STEPS (0: none)
  std::string init_from;             // --init-from FILE: warm-start the actor from a backbone file
  double init_log_std{-0.5};         // --init-log-std
  int critic_warmup{0};              // --critic-warmup ITERATIONS (actor frozen)
};
int run_train_ppo(const TrainPpoOptions& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift train dp --task T --out FILE [--seed S] [--demos N] [--iterations N] [--batch N]
//  [--down-dims 32,64,128] [--ddim-steps N] [--lr X] [--threads N] [--progress M]`: a Diffusion Policy
// (policy/dp.hpp) from the scripted expert's demonstrations; the file is the backbone dp:FILE
struct TrainDpCliOptions {
  std::string task;                 // --task
  std::string profile{"maniskill"}; // --profile
  std::uint64_t seed{20260718};     // --seed
  int demos{100};                   // --demos expert episodes
  int iterations{1000};             // --iterations optimiser steps
  int batch{64};                    // --batch
  std::string down_dims{"32,64,128"};  // --down-dims U-Net widths, comma separated
  int ddim_steps{0};                // --ddim-steps sampler of the policy (0: DDPM, 100 steps)
  double learning_rate{1e-4};       // --lr AdamW peak step size
  unsigned threads{0};              // --threads (0: all cores)
  std::string out;                  // --out FILE (.asdp)
  std::string progress{"auto"};     // --progress auto|bar|lines|off
};
int run_train_dp(const TrainDpCliOptions& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

// `actionshift gate0 --backbone B --task T --episodes N [--seed S] [--floor F] [--rule R]
//  [--threads N] [--json] [--out FILE] [--backbones-dir DIR] [--step-timeout S]`
struct Gate0Options {
  std::string backbone{"expert"};   // --backbone
  std::string task;                 // --task
  std::string profile{"maniskill"}; // --profile
  std::int64_t episodes{300};       // --episodes
  std::uint64_t seed{20260718};     // --seed
  double floor{-1.0};               // --floor (< 0: the task's reference floor)
  std::string rule{"wilson_lower"}; // --rule wilson_lower|point_estimate
  unsigned threads{0};              // --threads (0: all cores)
  bool json{false};                 // --json: print the verdict file instead of text
  std::string out;                  // --out FILE: write the verdict file
  std::string backbones_dir;        // --backbones-dir ("" → default)
  double step_timeout_s{10.0};      // --step-timeout (external policies)
  std::string progress{"auto"};     // --progress auto|bar|lines|off (as `run`; --quiet = off)
  RobotOptions robot;               // --robot/--package
};
int run_gate0(const Gate0Options& options, std::ostream& out = std::cout, std::ostream& err = std::cerr);

}  // namespace actionshift::cli
