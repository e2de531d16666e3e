// Gate 0: competence floor and identity-wrapper parity (reference section 8.1)
#include "actionshift/policy/gate0.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/vocabulary.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace actionshift::policy {
namespace {

std::string fmt4(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4f", x);
  return buf;
}

nlohmann::json wilson_json(const Wilson& w) {
  return {{"successes", w.successes}, {"total", w.total}, {"rate", w.rate},
          {"lower", w.lower},         {"upper", w.upper}, {"confidence", w.confidence}};
}

}  // namespace

Wilson wilson(std::int64_t s, std::int64_t n) {
  if (n <= 0) throw std::invalid_argument("at least one episode is required");
  if (s < 0 || s > n) throw std::invalid_argument("successes must lie in [0, total]");
  return actionshift::wilson_interval(s, n);
}

double gate0_floor(sim::TaskId task) { return sim::task_description(task).gate0_floor; }

std::string_view gate0_rule_name(Gate0Rule rule) {
  return rule == Gate0Rule::kWilsonLower ? "wilson_lower" : "point_estimate";
}

Gate0Rule parse_gate0_rule(std::string_view name) {
  if (name == "wilson_lower") return Gate0Rule::kWilsonLower;
  if (name == "point_estimate") return Gate0Rule::kPointEstimate;
  throw InputError("", "rule", "unknown competence rule '" + std::string(name) + "' (valid: wilson_lower, point_estimate)");
}

Gate0Competence gate0_competence(std::int64_t s, std::int64_t n, double floor, Gate0Rule rule) {
  Gate0Competence c;
  c.floor = floor;
  c.rule = rule;
  c.interval = wilson(s, n);
  const double stat = rule == Gate0Rule::kWilsonLower ? c.interval.lower : c.interval.rate;
  c.passed = stat >= floor;
  if (!c.passed)
    c.reason = rule == Gate0Rule::kWilsonLower
                   ? "success Wilson lower bound " + fmt4(c.interval.lower) + " below floor " + fmt4(floor)
                   : "success " + fmt4(c.interval.rate) + " below floor " + fmt4(floor);
  return c;
}

Gate0Parity gate0_parity(std::int64_t rs, std::int64_t rn, std::int64_t ws, std::int64_t wn, double tolerance) {
  Gate0Parity p;
  p.reference = wilson(rs, rn);
  p.wrapped = wilson(ws, wn);
  p.tolerance = tolerance;
  p.absolute_difference = std::abs(p.reference.rate - p.wrapped.rate);
  p.two_point_rule = p.absolute_difference <= tolerance + 1e-12;
  p.overlap_rule = std::max(p.reference.lower, p.wrapped.lower) <= std::min(p.reference.upper, p.wrapped.upper);
  p.passed = p.two_point_rule || p.overlap_rule;
  if (!p.passed)
    p.reason = "absolute success difference " + fmt4(p.absolute_difference) + " exceeds " + fmt4(tolerance) +
               " and CIs do not overlap";
  return p;
}

Gate0Verdict gate0_verdict(std::string_view backbone, std::string_view sha, sim::TaskId task,
                           const std::vector<EpisodeOutcome>& unwrapped, const std::vector<EpisodeOutcome>& identity,
                           double floor, Gate0Rule rule) {
  if (unwrapped.empty() || identity.empty()) throw std::invalid_argument("at least one episode is required");
  auto count = [](const std::vector<EpisodeOutcome>& v, auto pred) {
    return static_cast<std::int64_t>(std::count_if(v.begin(), v.end(), pred));
  };
  auto success = [](const EpisodeOutcome& e) { return e.success_once; };
  auto flagged = [](const EpisodeOutcome& e) { return e.safety != sim::SafetyFlag::kNone; };
  Gate0Verdict v;
  v.backbone = std::string(backbone);
  v.backbone_sha256 = std::string(sha);
  v.task = std::string(sim::task_name(task));
  v.episodes = static_cast<std::int64_t>(unwrapped.size());
  const std::int64_t su = count(unwrapped, success), nu = v.episodes;
  v.competence = gate0_competence(su, nu, floor, rule);
  v.identity_parity = gate0_parity(su, nu, count(identity, success), static_cast<std::int64_t>(identity.size()));
  v.success_at_end_unwrapped = count(unwrapped, [](const EpisodeOutcome& e) { return e.success_at_end; });
  v.flagged_unwrapped = count(unwrapped, flagged);
  v.flagged_identity = count(identity, flagged);
  v.passed = v.competence.passed && v.identity_parity.passed;
  v.decision = verdict_name(v.passed ? Verdict::kAdvance : Verdict::kExclude);
  if (!v.competence.passed) v.reason = "competence: " + v.competence.reason;
  else if (!v.identity_parity.passed) v.reason = "identity parity: " + v.identity_parity.reason;
  return v;
}

void check_gate0_run(const Gate0Run& run) {
  if (run.episodes <= 0) throw InputError("", "episodes", "at least one episode is required");
  sim::check_horizon(run.horizon, "");
}

Gate0Verdict run_gate0(const Policy& policy, const Gate0Run& run) {
  check_gate0_run(run);
  if (run.robot && run.robot_sha256.empty())
    throw InputError("gate0", "robot_sha256", "a robot description needs its content hash (sim::load_robot_source), which the verdict records");
  sim::EnvConfig config = sim::profile_config(run.profile);
  config.horizon = run.horizon;
  auto model = sim::EnvModel::make(policy.task(), config, run.robot);
  RolloutOptions o;
  o.seed = run.seed;
  o.contract_index = 0;
  o.episodes = run.episodes;
  o.threads = run.threads;
  if (run.progress) o.progress = [&run](std::int64_t k, std::int64_t n) { run.progress(k, 2 * n); };
  const auto unwrapped = run_episodes(policy, model, o);
  o.contract = Contract::identity();
  if (run.progress) o.progress = [&run](std::int64_t k, std::int64_t n) { run.progress(n + k, 2 * n); };
  const auto identity = run_episodes(policy, model, o);
  const double floor = run.floor < 0 ? gate0_floor(policy.task()) : run.floor;
  Gate0Verdict v = gate0_verdict(policy.name(), policy.sha256(), policy.task(), unwrapped, identity, floor, run.rule);
  v.seed = run.seed;
  v.profile = run.profile;
  v.horizon = run.horizon;
  v.robot_sha256 = run.robot ? run.robot_sha256 : std::string();
  return v;
}

nlohmann::json gate0_to_json(const std::vector<Gate0Verdict>& verdicts) {
  auto parity_json = [](const Gate0Parity& p) -> nlohmann::json {
    return {{"reference", wilson_json(p.reference)}, {"wrapped", wilson_json(p.wrapped)},
            {"tolerance", p.tolerance},             {"absolute_difference", p.absolute_difference},
            {"two_point_rule", p.two_point_rule},   {"overlap_rule", p.overlap_rule},
            {"passed", p.passed},                   {"reason", p.reason}};
  };
  nlohmann::json j = {{"schema_version", "1.0"}, {"gate", "gate0"}, {"cells", nlohmann::json::object()}};
  bool all = !verdicts.empty();
  for (const auto& v : verdicts) {
    all = all && v.passed;
    const std::string key = v.backbone + "/" + v.task + (v.robot_sha256.empty() ? "" : "@robot:" + v.robot_sha256.substr(0, 12));
    nlohmann::json& cell = j["cells"][key];
    cell = {
        {"backbone", v.backbone},
        {"backbone_sha256", v.backbone_sha256},
        {"task", v.task},
        {"seed", v.seed},
        {"profile", v.profile},
        {"episodes", v.episodes},
        {"verdict", verdict_name(v.passed ? Verdict::kPass : Verdict::kFail)},
        {"decision", v.decision},
        {"reason", v.reason},
        {"competence",
         {{"floor", v.competence.floor},
          {"rule", std::string(gate0_rule_name(v.competence.rule))},
          {"interval", wilson_json(v.competence.interval)},
          {"passed", v.competence.passed},
          {"reason", v.competence.reason}}},
        {"identity_parity", parity_json(v.identity_parity)},
        {"oracle_parity", nullptr},
        {"success_at_end", v.success_at_end_unwrapped},
        {"safety_flagged", {{"unwrapped", v.flagged_unwrapped}, {"identity", v.flagged_identity}}}};
    if (!v.robot_sha256.empty()) cell["robot"] = {{"sha256", v.robot_sha256}};
    if (v.horizon > 0) cell["horizon"] = v.horizon;  // only an override, so verdicts at the task's horizon keep their bytes
  }
  j["passed"] = all;
  return j;
}

}  // namespace actionshift::policy
