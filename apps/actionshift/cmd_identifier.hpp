#pragma once
// `actionshift train identifier`: the learned identifiers of the unprivileged tier (docs/identifiers.md).
// Plain function (no CLI11 here); 0 ok, 2 bad input.

#include "commands.hpp"

#include <cstdint>
#include <iostream>
#include <string>

namespace actionshift::cli {

// `actionshift train identifier --kind osi|probe_osi|recurrent_osi --task T [--seed S] [--excitation E]
//  [--episodes N] [--train-steps N] [--threads N] [--out FILE] [--verdicts FILE]`
struct TrainIdentifierCliOptions {
  std::string kind;                   // --kind
  std::string task{"pick_cube"};      // --task
  std::string profile{"maniskill"};   // --profile
  std::uint64_t seed{20260720};       // --seed
  std::string excitation{"expert"};   // --excitation expert|random
  int episodes{4};                    // --episodes per training contract
  int train_steps{3000};              // --train-steps (Adam)
  int max_contracts{0};               // --max-contracts (smoke runs; 0: all)
  unsigned threads{0};                // --threads (data collection)
  std::string out;                    // --out FILE ("" → configs/identifiers/<task>.<kind>.asid)
  std::string verdicts;               // --verdicts FILE: the held-out verdicts as JSON
  bool quiet{false};                  // --quiet: no progress lines
};
int run_train_identifier(const TrainIdentifierCliOptions& o, std::ostream& out = std::cout, std::ostream& err = std::cerr);

}  // namespace actionshift::cli
