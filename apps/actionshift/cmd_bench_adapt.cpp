// actionshift bench adapt: the per-step cost of an adapter configuration on synthetic episodes
// (adapt/bench.hpp), with the task's built-in response calibration as the response model.
#include "cmd_bench_adapt.hpp"
#include "commands.hpp"

#include "actionshift/adapt/bench.hpp"
#include "actionshift/adapt/calibration.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/data/builtin_manifests.hpp"

#include <cstdio>
#include <iostream>

namespace actionshift::cli {

int run_bench_adapt(const BenchAdaptOptions& o) {
  adapt::AdapterBenchConfig cfg = o.bench;
  const std::string& method = cfg.method;
  cfg.params = parse_json_input(o.params, "command line", "--params");
  if (!cfg.params.is_object()) throw InputError("", "--params", "must be a JSON object");
  cfg.params = adapt::resolve_method_params(method, cfg.params);  // unknown method / parameter: InputError
  if (adapt::method_needs_pool(method)) {
    const Manifest m = data::resolve_manifest(o.pool);
    if (!m.is_pool()) throw InputError(o.pool, "kind", "is a split manifest, not a pool");
    cfg.pool = m.contracts();
  }
  const auto text = data::builtin_calibration_text(o.task, o.profile);
  if (!text) throw InputError("--task", o.task, "no built-in calibration for this task on profile '" + o.profile + "'");
  cfg.model = adapt::ResponseCalibration::from_json(std::string(*text), "builtin:calibration/" + o.profile + "/" + o.task).model();
  const adapt::AdapterBenchResult r = adapt::bench_adapter(cfg);
  if (o.json) {
    nlohmann::json j = r.to_json();
    j["pool"] = adapt::method_needs_pool(method) ? nlohmann::json(o.pool) : nlohmann::json(nullptr);
    j["task"] = o.task;
    j["profile"] = o.profile;
    j["episodes"] = cfg.episodes;
    j["steps"] = cfg.steps;
    j["repetitions"] = cfg.repetitions;
    std::cout << j.dump() << "\n";
    return kOk;
  }
  std::printf("%s on %s (%d hypotheses), %s/%s response model: %d episodes x %d steps, medians of %d repetitions\n",
              method.c_str(), adapt::method_needs_pool(method) ? o.pool.c_str() : "no pool", r.hypotheses, o.profile.c_str(),
              o.task.c_str(), cfg.episodes, cfg.steps, cfg.repetitions);
  std::printf("  first encode (selection from the uniform belief) %10.2f us\n", r.first_select_us);
  std::printf("  encode on a probe step                           %10.2f us  (%.2f probes per episode)\n", r.probe_encode_us,
              r.probes_per_episode);
  std::printf("  encode on a task step                            %10.2f us\n", r.act_encode_us);
  std::printf("  observe (belief update)                          %10.2f us\n", r.observe_us);
  std::printf("  per control step (encode + observe)              %10.2f us\n", r.step_us);
  return kOk;
}

}  // namespace actionshift::cli
