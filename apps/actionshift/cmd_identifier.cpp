#include "cmd_identifier.hpp"

#include "actionshift/adapt/identifier.hpp"
#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/eval/identifier_train.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/task.hpp"

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace actionshift::cli {

int run_train_identifier(const TrainIdentifierCliOptions& o, std::ostream& out, std::ostream& err) {
  const auto kind = adapt::parse_identifier_kind(o.kind);
  if (!kind) throw InputError("--kind", o.kind, "must be osi, probe_osi or recurrent_osi");
  eval::TrainIdentifierOptions t;
  t.kind = *kind;
  t.task = o.task;
  t.profile = o.profile;
  t.seed = o.seed;
  t.excitation = o.excitation;
  t.episodes_per_contract = o.episodes;
  t.train_steps = o.train_steps;
  t.max_contracts = o.max_contracts;
  t.threads = o.threads;
  if (o.episodes <= 0) throw InputError("--episodes", std::to_string(o.episodes), "must be positive");
  if (o.train_steps < 0) throw InputError("--train-steps", std::to_string(o.train_steps), "must be nonnegative");
  if (o.max_contracts < 0) throw InputError("--max-contracts", std::to_string(o.max_contracts), "must be nonnegative");
  if (o.excitation != "expert" && o.excitation != "random") throw InputError("--excitation", o.excitation, "must be expert or random");
  (void)sim::parse_task(o.task);          // bad input is one line, before anything is printed
  (void)sim::profile_config(o.profile);
  const std::string path = o.out.empty() ? adapt::identifier_weights_path(o.task, *kind) : o.out;
  require_writable_output(path);  // before the rollouts and the training, not after them
  if (!o.verdicts.empty()) require_writable_output(o.verdicts);
  std::ostringstream cmd;
  cmd << "actionshift train identifier --kind " << o.kind << " --task " << o.task << " --seed " << o.seed << " --excitation "
      << o.excitation << " --episodes " << o.episodes << " --train-steps " << o.train_steps << " --profile " << o.profile;
  if (o.max_contracts > 0) cmd << " --max-contracts " << o.max_contracts;
  err << "train identifier: " << o.kind << " on " << o.task << " (" << o.profile << "), "
      << eval::identifier_parameter_count(*kind, t) << " parameters, seed " << o.seed << ", excitation " << o.excitation << "\n";
  auto result = eval::train_identifier(t, [&](const std::string& line) {
    if (!o.quiet) err << "  " << line << "\n";
  });
  result.weights.training = {{"command", cmd.str()},
                             {"seed", o.seed},
                             {"profile", o.profile},
                             {"excitation", o.excitation},
                             {"contracts", "identifier_training (train list; held-out: its test list)"},
                             {"episodes_per_contract", o.episodes},
                             {"rollout_steps", t.steps},
                             {"train_steps", o.train_steps},
                             {"batch", t.batch},
                             {"learning_rate", t.learning_rate},
                             {"final_loss", std::round(result.final_loss * 1e4) / 1e4},
                             {"heldout", result.heldout.to_json()}};
  adapt::save_identifier(result.weights, path);
  const std::string bytes = adapt::serialize_identifier(result.weights);
  // the held-out verdicts: field accuracy per horizon
  out << "held-out field accuracy (" << result.heldout.contracts << " contracts, " << result.heldout.episodes << " episodes)\n";
  out << "| steps |";
  for (const char* f : adapt::kFieldNames) out << " " << f << " |";
  out << " exact |\n|---:|";
  for (std::size_t i = 0; i < adapt::kFieldNames.size(); ++i) out << "---:|";
  out << "---:|\n";
  for (std::size_t h = 0; h < result.heldout.horizons.size(); ++h) {
    out << "| " << result.heldout.horizons[h] << " |";
    for (double a : result.heldout.accuracy[h]) out << " " << std::fixed << std::setprecision(3) << a << " |";
    out << " " << std::fixed << std::setprecision(3) << result.heldout.exact[h] << " |\n";
  }
  const std::string sha = sha256_hex(bytes);
  if (!o.verdicts.empty()) {
    nlohmann::json v = {{"kind", o.kind},          {"task", o.task},
                        {"seed", o.seed},          {"excitation", o.excitation},
                        {"profile", o.profile},    {"command", cmd.str()},
                        {"weights", path},         {"weights_sha256", sha},
                        {"parameters", result.weights.parameter_count()},
                        {"wall_seconds", std::round(result.wall_seconds * 10) / 10},
                        {"heldout", result.heldout.to_json()}};
    write_file_atomic(o.verdicts, v.dump(2) + "\n");
  }
  out << "wrote " << path << " (" << bytes.size() << " bytes, " << result.weights.parameter_count() << " parameters, sha256 " << sha
      << ") in " << std::fixed << std::setprecision(1) << result.wall_seconds << " s\n";
  return kOk;
}

}  // namespace actionshift::cli
