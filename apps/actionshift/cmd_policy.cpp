// `train bc`, `train ppo` and `gate0`: thin wrappers over the policy layer (their library settings are
// bound by cli_policy.cpp and checked by the library)
#include "cmd_policy.hpp"

#include "cmd_eval.hpp"

#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/policy/dp.hpp"
#include "actionshift/policy/gate0.hpp"
#include "actionshift/policy/ppo.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/policy/train.hpp"
#include "actionshift/sim/robot_source.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace actionshift::cli {
namespace {

std::string fmt(double x, int digits = 3) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << x;
  return s.str();
}

std::vector<int> parse_hidden(const std::string& text);

std::string hidden_text(const std::vector<int>& widths) {
  std::string s;
  for (int w : widths) s += (s.empty() ? "" : "-") + std::to_string(w);
  return s;
}

}  // namespace

int run_train_bc(TrainBcOptions o, std::ostream& out, std::ostream& err) {
  try {
    policy::TrainBcOptions& t = o.train;  // --profile (checked while parsing), --seed, --iterations, ...
    t.task = sim::parse_task(o.task);
    t.hidden = parse_hidden(o.hidden);
    policy::check_train_bc_options(t);
    const std::string backbone = t.delay_aware ? "mlp-delay-aware" : "mlp";
    const std::string path = o.out.empty() ? policy::mlp_weights_path(backbone, t.task) : o.out;
    require_writable_output(path);  // before the DAgger iterations, not after them
    std::string command = "actionshift train bc --task " + o.task + (t.delay_aware ? " --delay-aware" : "") +
                          " --seed " + std::to_string(t.seed) + " --iterations " + std::to_string(t.iterations) +
                          " --episodes " + std::to_string(t.episodes_per_iteration) + " --steps " + std::to_string(t.steps_per_iteration) +
                          (o.hidden == TrainBcOptions{}.hidden ? "" : " --hidden " + o.hidden) + " --profile " + t.profile;
    err << "train bc: " << o.task << " " << backbone << ", layers " << sim::observation_layout(t.task).size() +
                                                                            (t.delay_aware ? 28 : 0)
        << "-" << hidden_text(t.hidden) << "-7, " << t.iterations << " DAgger iterations x " << t.episodes_per_iteration << " episodes, seed " << t.seed << "\n";
    if (o.progress != "off") (void)parse_progress_mode(o.progress);  // validates the mode
    auto result = policy::train_bc(t, [&err, &o, &t](const policy::TrainIteration& it) {
      if (o.progress == "off") return;
      err << "  iteration " << it.iteration + 1 << "/" << t.iterations << ": beta " << fmt(it.beta, 3) << ", rollouts "
          << it.successes << "/" << it.episodes << " success, data " << it.samples << ", loss " << fmt(it.loss, 5)
          << ", " << fmt(it.seconds, 1) << " s\n";
    });
    result.weights.training = {{"command", command},
                               {"seed", t.seed},
                               {"algorithm", "DAgger from the scripted expert, Adam, MSE (gripper weight 2)"},
                               {"iterations", t.iterations},
                               {"episodes_per_iteration", t.episodes_per_iteration},
                               {"steps_per_iteration", t.steps_per_iteration},
                               {"batch_size", t.batch_size},
                               {"learning_rate", t.learning_rate},
                               {"teacher", t.delay_aware ? "expert-delay-aware (true lag)" : "expert"},
                               {"lags", t.delay_aware ? nlohmann::json({0, 1, 2, 4}) : nlohmann::json({0})},
                               {"final_rollout_success", result.iterations.back().successes},
                               {"final_rollout_episodes", result.iterations.back().episodes}};
    if (o.hidden != TrainBcOptions{}.hidden) result.weights.training["hidden"] = t.hidden;  // default: as before
    policy::save_mlp(result.weights, path);
    const std::string bytes = policy::serialize_mlp(result.weights);
    out << "wrote " << path << " (" << bytes.size() << " bytes, " << result.weights.parameter_count()
        << " parameters, sha256 " << sha256_hex(bytes) << ") in " << fmt(result.wall_seconds, 1) << " s\n";
    return 0;
  } catch (const std::invalid_argument& e) {
    err << "actionshift: error: " << e.what() << "\n";
    return 2;
  }
}

int run_train_dp(const TrainDpCliOptions& o, std::ostream& out, std::ostream& err) {
  try {
    policy::TrainDpOptions t = o.dp;
    t.task = sim::parse_task(o.task);
    try {
      t.down_dims = parse_hidden(o.down_dims);
    } catch (const InputError& e) {
      throw InputError("", "down-dims", e.reason());
    }
    policy::check_train_dp_options(t);
    policy::DpArch arch;
    arch.obs_dim = sim::observation_layout(t.task).size();
    arch.down_dims = t.down_dims;
    if (o.out.empty()) throw InputError("", "out", "a weight file is required (the backbone is then dp:FILE)");
    require_writable_output(o.out);
    if (o.progress != "off") (void)parse_progress_mode(o.progress);  // validates the mode
    const int resume_at = policy::check_train_dp_checkpoint(t);  // a bad checkpoint is refused before anything is printed
    const std::string command = "actionshift train dp --task " + o.task + " --seed " + std::to_string(t.seed) + " --demos " +
                                std::to_string(t.demos) + " --iterations " + std::to_string(t.iterations) + " --batch " +
                                std::to_string(t.batch_size) + " --down-dims " + o.down_dims + " --ddim-steps " +
                                std::to_string(t.ddim_steps) + " --lr " + fmt(t.learn.learning_rate, 8) + " --profile " + t.profile;
    err << "train dp: " << o.task << ", U-Net " << hidden_text(t.down_dims) << " (" << policy::dp_parameter_count(arch)
        << " parameters), " << t.demos << " expert demos, " << t.iterations << " iterations x batch " << t.batch_size << ", seed "
        << t.seed << "\n";
    if (resume_at > 0) err << "train dp: continuing from " << t.checkpoint << " at iteration " << resume_at << "\n";
    // the training curve beside the file (the file itself holds no timing, so it re-trains byte for byte)
    const std::string stem = o.out.size() > 5 && o.out.ends_with(".asdp") ? o.out.substr(0, o.out.size() - 5) : o.out;
    const std::string curve_path = stem + ".curve.jsonl";
    auto result = policy::train_dp(t, [&err, &o, &t](const policy::TrainDpProgress& p) {
      if (o.progress == "off") return;
      err << "  iteration " << p.iteration << "/" << t.iterations << ": loss " << fmt(p.loss, 5) << ", " << fmt(p.seconds, 1) << " s\n";
    });
    // the whole curve, the part before a resume included (it travels in the checkpoint)
    std::ostringstream curve;
    for (const auto& p : result.curve)
      curve << nlohmann::json{{"iteration", p.iteration}, {"loss", p.loss}, {"seconds", p.seconds}}.dump() << "\n";
    const double per_iteration = result.train_seconds / t.iterations;
    curve << nlohmann::json{{"command", command},
                            {"collect_seconds", result.collect_seconds},
                            {"train_seconds", result.train_seconds},
                            {"seconds_per_iteration", per_iteration},
                            {"resumed_at", result.resumed_at},
                            {"threads", policy::resolve_threads(t.threads)}}
                 .dump()
          << "\n";
    result.weights.training = {{"command", command},
                               {"seed", t.seed},
                               {"algorithm", "DDPM noise prediction on the scripted expert's demonstrations; AdamW, warm-up + cosine, EMA"},
                               {"demos", t.demos},
                               {"demo_successes", result.demo_successes},
                               {"windows", result.windows},
                               {"iterations", t.iterations},
                               {"batch_size", t.batch_size},
                               {"learning_rate", t.learn.learning_rate},
                               {"warmup_steps", t.learn.warmup_steps},
                               {"weight_decay", t.learn.weight_decay},
                               {"ema_max_decay", t.learn.ema_max_decay},
                               {"final_loss", result.final_loss}};
    policy::save_dp(result.weights, o.out);
    write_file_atomic(curve_path, curve.str());
    if (!t.checkpoint.empty()) {  // the weight file supersedes it; failing to remove it loses nothing
      std::error_code ec;
      std::filesystem::remove(t.checkpoint, ec);
      if (ec) err << "train dp: note: could not remove the checkpoint " << t.checkpoint << ": " << ec.message() << "\n";
    }
    const std::string bytes = policy::serialize_dp(result.weights);
    err << "train dp: " << result.demo_successes << "/" << t.demos << " demos kept, " << result.windows << " windows; "
        << fmt(per_iteration, 3) << " s per iteration (batch " << t.batch_size << ")\n";
    out << "wrote " << o.out << " (" << bytes.size() << " bytes, " << result.weights.params.size() << " parameters, sha256 "
        << sha256_hex(bytes) << ") and " << curve_path << " in " << fmt(result.collect_seconds + result.train_seconds, 1)
        << " s; backbone dp:" << o.out << "\n";
    return 0;
  } catch (const std::invalid_argument& e) {
    err << "actionshift: error: " << e.what() << "\n";
    return 2;
  }
}

namespace {
std::vector<int> parse_hidden(const std::string& text) {
  std::vector<int> widths;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    int v = 0;
    try {
      v = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || item.empty() || v <= 0 || v > 4096)
      throw InputError("", "hidden", "expected comma-separated layer widths in [1, 4096] (got '" + text + "')");
    widths.push_back(v);
  }
  if (widths.empty()) throw InputError("", "hidden", "at least one hidden layer is required");
  return widths;
}
}  // namespace

int run_train_ppo(TrainPpoOptions o, std::ostream& out, std::ostream& err) {
  try {
    policy::PpoOptions& p = o.ppo;  // --profile (checked while parsing), --seed, --envs, --lr, ...
    p.task = sim::parse_task(o.task);
    p.hidden = parse_hidden(o.hidden);
    p.bootstrap_success = !o.terminal_success;
    policy::check_ppo_options(p);
    std::string init_sha;
    if (!o.init_from.empty()) {
      const auto init = policy::MlpPolicy::from_file(o.init_from);
      auto w = std::make_shared<const policy::MlpWeights>(init->weights());
      if (w->task != p.task)
        throw InputError(o.init_from, "task", "is " + std::string(sim::task_name(w->task)) + ", the run trains " + o.task);
      const std::vector<int> hidden(w->layers.begin() + 1, w->layers.end() - 1);
      if (hidden != p.hidden) throw InputError(o.init_from, "layers", "hidden widths differ from --hidden " + o.hidden);
      if (w->history != 0 && !p.delay_aware)
        throw InputError(o.init_from, "history", "a delay-aware network cannot start a reactive run (add --delay-aware)");
      init_sha = init->sha256();
      p.init_actor = std::move(w);
    }
    const eval::ProgressMode mode = parse_progress_mode(o.progress);
    const bool bar = mode == eval::ProgressMode::bar || (mode == eval::ProgressMode::automatic && isatty(2));
    const std::string path = o.out.empty() ? policy::mlp_weights_path(p.delay_aware ? "ppo-delay-aware" : "ppo", p.task) : o.out;
    require_writable_output(path);  // before the run, not after it
    const std::string stem = path.size() > 6 && path.ends_with(".asmlp") ? path.substr(0, path.size() - 6) : path;
    const std::string curve_path = o.curve.empty() ? stem + ".curve.jsonl" : o.curve;
    std::ofstream curve(curve_path, std::ios::trunc);
    if (!curve) throw InputError(curve_path, "", "cannot write the training curve");
    // the command that reproduces a run of `steps` environment steps (a checkpoint names its own): the
    // total steps themselves, or, when the learning-rate schedule depends on the total (--anneal-lr),
    // the same total and --stop-after
    const std::int64_t full_steps = std::max<std::int64_t>(1, p.total_steps / (static_cast<std::int64_t>(p.num_envs) * p.num_steps)) *
                                    p.num_envs * p.num_steps;
    auto command = [&o, &p, full_steps](std::int64_t steps) {
      std::ostringstream cmd;
      cmd << "actionshift train ppo --task " << o.task << " --profile " << p.profile << " --seed " << p.seed << " --total-steps "
          << (p.anneal_lr ? p.total_steps : steps) << " --envs " << p.num_envs << " --rollout-steps " << p.num_steps << " --minibatches " << p.num_minibatches
          << " --epochs " << p.update_epochs << " --lr " << p.learning_rate << " --gamma " << p.gamma << " --gae-lambda " << p.gae_lambda
          << " --target-kl " << p.target_kl << " --hidden " << o.hidden << " --eval-every " << p.eval_every
          << " --eval-episodes " << p.eval_episodes;
      if (p.delay_aware) cmd << " --delay-aware";
      if (p.anneal_lr) cmd << " --anneal-lr";
      if (o.terminal_success) cmd << " --terminal-success";
      if (p.anneal_lr && steps < full_steps) cmd << " --stop-after " << steps;
      if (!o.init_from.empty()) cmd << " --init-from " << o.init_from;
      if (p.init_log_std != -0.5) cmd << " --init-log-std " << p.init_log_std;
      if (p.critic_warmup > 0) cmd << " --critic-warmup " << p.critic_warmup;
      return cmd.str();
    };
    nlohmann::json provenance = {
        {"command", command(p.total_steps)},
        {"seed", p.seed},
        {"algorithm", "PPO (clipped objective, GAE, Adam), Gaussian actor, state-independent log std; backbone = actor mean"},
        {"profile", p.profile},
        {"reward", "normalized_dense"},
        {"num_envs", p.num_envs},
        {"rollout_steps", p.num_steps},
        {"minibatches", p.num_minibatches},
        {"epochs", p.update_epochs},
        {"learning_rate", p.learning_rate},
        {"gamma", p.gamma},
        {"gae_lambda", p.gae_lambda},
        {"clip_coef", p.clip_coef},
        {"vf_coef", p.vf_coef},
        {"ent_coef", p.ent_coef},
        {"max_grad_norm", p.max_grad_norm},
        {"target_kl", p.target_kl},
        {"init_log_std", p.init_log_std}};
    if (p.delay_aware) provenance["delay_aware"] = {{"history", policy::kHistoryLength}, {"training_lags", policy::kTrainingLags}};
    if (p.anneal_lr) provenance["anneal_lr"] = true;
    if (!o.init_from.empty()) {
      provenance["init_from"] = {{"path", o.init_from}, {"sha256", init_sha}};
      if (p.init_actor->training.contains("env_steps")) provenance["init_from"]["env_steps"] = p.init_actor->training["env_steps"];
      provenance["critic_warmup"] = p.critic_warmup;
    }
    provenance["success"] = o.terminal_success ? "terminal" : "bootstrapped with the critic's value of the final observation";
    const std::int64_t per_iter = static_cast<std::int64_t>(p.num_envs) * p.num_steps;
    const std::int64_t iterations = std::max<std::int64_t>(1, p.total_steps / per_iter);
    err << "train ppo: " << o.task << (p.delay_aware ? " (delay-aware)" : "") << ", layers "
        << sim::observation_layout(p.task).size() + (p.delay_aware ? policy::kHistoryLength * kActionDim : 0) << "-" << o.hidden << "-7 (actor and critic), "
        << iterations << " iterations x " << p.num_envs << " envs x " << p.num_steps << " steps = " << iterations * per_iter
        << " env steps, seed " << p.seed << ", " << counted(static_cast<std::size_t>(policy::resolve_threads(p.threads)), "thread") << "\n";
    double last_eval = -1.0, last_eval_return = 0.0, best_eval = -1.0;
    std::int64_t best_steps = 0;
    const std::string best_path = stem + ".best.asmlp";
    auto result = policy::train_ppo(
        p, provenance,
        [&](const policy::PpoIteration& it) {
          if (it.eval_success >= 0) {
            last_eval = it.eval_success;
            last_eval_return = it.eval_return;
          }
          nlohmann::json line = {{"iteration", it.iteration + 1},
                                 {"env_steps", it.env_steps},
                                 {"seconds", it.seconds},
                                 {"steps_per_second", it.seconds > 0 ? static_cast<double>(it.env_steps) / it.seconds : 0.0},
                                 {"episodes", it.episodes},
                                 {"successes", it.successes},
                                 {"policy_loss", it.policy_loss},
                                 {"value_loss", it.value_loss},
                                 {"approx_kl", it.approx_kl},
                                 {"clip_fraction", it.clip_fraction},
                                 {"epochs", it.epochs},
                                 {"mean_std", it.mean_std}};
          line["mean_return"] = std::isfinite(it.mean_return) ? nlohmann::json(it.mean_return) : nlohmann::json(nullptr);
          if (it.eval_success >= 0) {
            line["eval_success_once"] = it.eval_success;
            line["eval_return"] = it.eval_return;
          }
          curve << line.dump() << "\n" << std::flush;
          if (mode == eval::ProgressMode::off) return;
          std::ostringstream l;
          l << "iteration " << it.iteration + 1 << "/" << iterations << ", " << it.env_steps << " steps, "
            << fmt(it.seconds > 0 ? static_cast<double>(it.env_steps) / it.seconds : 0.0, 0) << " steps/s: train success "
            << it.successes << "/" << it.episodes << ", return "
            << (std::isfinite(it.mean_return) ? fmt(it.mean_return, 2) : std::string("-")) << "; eval success "
            << (last_eval >= 0 ? fmt(last_eval, 3) : std::string("-")) << ", return " << (last_eval >= 0 ? fmt(last_eval_return, 2) : std::string("-"))
            << "; kl " << fmt(it.approx_kl, 4) << ", std " << fmt(it.mean_std, 3);
          if (bar)
            err << "\r\033[K" << l.str() << (it.iteration + 1 == iterations ? "\n" : "") << std::flush;
          else
            err << "  " << l.str() << "\n";
        },
        [&](const policy::MlpWeights& w) {
          policy::MlpWeights c = w;
          c.training["command"] = command(w.training.at("env_steps").get<std::int64_t>());
          policy::save_mlp(c, path);
          // the best evaluation so far is kept beside the latest (training's own evaluation episodes,
          // never Gate 0's), so a late collapse does not lose the peak
          const double s = w.training.value("eval_success_once", -1.0);
          if (s > best_eval) {
            best_eval = s;
            best_steps = w.training.at("env_steps").get<std::int64_t>();
            policy::save_mlp(c, best_path);
          }
        });
    result.actor.training["command"] = command(result.actor.training.at("env_steps").get<std::int64_t>());
    policy::save_mlp(result.actor, path);
    const std::string bytes = policy::serialize_mlp(result.actor);
    out << "wrote " << path << " (" << bytes.size() << " bytes, " << result.actor.parameter_count() << " parameters, sha256 "
        << sha256_hex(bytes) << ") and " << curve_path << " in " << fmt(result.wall_seconds, 1) << " s; final eval success "
        << (last_eval >= 0 ? fmt(last_eval, 3) : std::string("-")) << "\n";
    if (best_eval >= 0)
      out << "best eval success " << fmt(best_eval, 3) << " at " << best_steps << " env steps: " << best_path << "\n";
    return 0;
  } catch (const std::invalid_argument& e) {
    err << "actionshift: error: " << e.what() << "\n";
    return 2;
  }
}

int run_gate0(Gate0Options o, std::ostream& out, std::ostream& err) {
  std::unique_ptr<policy::Policy> pol;
  policy::Gate0Run& run = o.run;  // --profile (checked while parsing), --episodes, --seed, --floor, --threads
  try {
    const sim::TaskId task = sim::parse_task(o.task);
    policy::check_gate0_run(run);
    run.rule = policy::parse_gate0_rule(o.rule);
    if (!o.out.empty()) require_writable_output(o.out);  // before the episodes, not after them
    policy::RegistryOptions reg;
    reg.backbones_dir = o.backbones_dir;
    reg.external.step_timeout_s = o.step_timeout_s;
    pol = policy::make_policy(o.backbone, task, reg);
    if (!o.robot.urdf.empty() || !o.robot.packages.empty()) {
      if (o.robot.urdf.empty()) throw InputError("--package", o.robot.packages.front(), "needs --robot URDF");
      const sim::RobotSource robot = sim::load_robot_source(o.robot.urdf, sim::parse_package_args(o.robot.packages));
      run.robot = robot.description;
      run.robot_sha256 = robot.sha256;  // the verdict names the description it certifies
    }
  } catch (const std::invalid_argument& e) {
    err << "actionshift: error: " << e.what() << "\n";
    return 2;
  } catch (const std::runtime_error& e) {
    err << "actionshift: error: " << e.what() << "\n";
    return 2;
  }
  eval::ProgressMode mode;
  try {
    mode = parse_progress_mode(o.progress);
  } catch (const std::invalid_argument& e) {
    err << "actionshift: error: " << e.what() << "\n";
    return 2;
  }
  if (mode == eval::ProgressMode::automatic)
    mode = ::isatty(STDERR_FILENO) ? eval::ProgressMode::bar : eval::ProgressMode::lines;
  const bool bar = mode == eval::ProgressMode::bar;
  const bool progress = mode != eval::ProgressMode::off;
  if (progress) {
    // a bar rewrites one line (a terminal only); lines mode prints a line per 10 %, never a carriage return
    run.progress = [&err, bar, last = std::int64_t{-1}](std::int64_t k, std::int64_t n) mutable {
      const std::int64_t pct = 100 * k / n;
      if (pct / 10 != last / 10 || k == n) {
        if (bar) err << "\rgate0: " << k << "/" << n << " episodes (" << pct << " %)" << (k == n ? "\n" : "") << std::flush;
        else err << "gate0: " << k << "/" << n << " episodes (" << pct << " %)\n" << std::flush;
        last = pct;
      }
    };
  }
  policy::Gate0Verdict v;
  try {
    v = policy::run_gate0(*pol, run);
  } catch (const std::exception& e) {
    if (bar) err << "\n";
    err << "actionshift: error: " << e.what() << "\n";
    return 2;
  }
  const nlohmann::json j = policy::gate0_to_json({v});
  if (!o.out.empty()) write_file_atomic(o.out, j.dump(2) + "\n");
  if (o.json) {
    out << j.dump(2) << "\n";
  } else {
    const auto& c = v.competence;
    const auto& p = v.identity_parity;
    out << "Gate 0: " << v.backbone << " on " << v.task << " (" << v.episodes << " episodes, seed " << v.seed
        << (v.horizon > 0 ? ", horizon " + std::to_string(v.horizon) : "") << (v.robot_sha256.empty() ? "" : ", robot " + v.robot_sha256.substr(0, 12)) << ")\n"
        << "  competence: success_once " << c.interval.successes << "/" << c.interval.total << " = " << fmt(c.interval.rate)
        << " [" << fmt(c.interval.lower) << ", " << fmt(c.interval.upper) << "], floor " << fmt(c.floor, 2) << " ("
        << policy::gate0_rule_name(c.rule) << "): " << (c.passed ? "pass" : "fail") << "\n"
        << "  parity: identity-wrapped " << p.wrapped.successes << "/" << p.wrapped.total << " = " << fmt(p.wrapped.rate)
        << " [" << fmt(p.wrapped.lower) << ", " << fmt(p.wrapped.upper) << "], |diff| " << fmt(p.absolute_difference, 4)
        << "; two-point rule " << (p.two_point_rule ? "pass" : "fail") << ", overlap rule "
        << (p.overlap_rule ? "pass" : "fail") << ": " << (p.passed ? "pass" : "fail") << "\n"
        << "  decision: " << v.decision << (v.reason.empty() ? "" : " (" + v.reason + ")") << "\n";
  }
  return v.passed ? 0 : 1;
}

}  // namespace actionshift::cli
