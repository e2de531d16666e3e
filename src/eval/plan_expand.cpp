// Experiment → Plan: every job of the grid resolved and validated; a single job by names
#include "actionshift/eval/plan_expand.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/sim/task.hpp"
#include "plan_detail.hpp"

#include <map>
#include <set>
#include <stdexcept>
#include <vector>

namespace actionshift::eval {

using detail::check_job_count;

JobSpec resolve_job(const JobRequest& q, const PlanResolver& resolver) {
  if (!resolver.split || !resolver.backbone) throw std::invalid_argument("resolve_job: resolver needs split and backbone");
  if (q.pool && !resolver.pool) throw InputError(q.source, "pool", "pools cannot be resolved here");
  const MethodEntry method = resolver.canonical_method ? resolver.canonical_method(q.method) : q.method;
  if (resolver.check_method) resolver.check_method(method);
  JobSpec job;
  job.task = q.task;
  job.split = resolver.split(q.task, q.split);
  job.method = method.name;
  job.method_params = resolver.method_params ? resolver.method_params(method) : method.params;
  if (resolver.method_plugin) job.method_plugin = resolver.method_plugin(method);
  job.backbone = resolver.backbone(q.task, q.backbone);
  if (q.pool && (!resolver.method_uses_pool || resolver.method_uses_pool(method))) job.pool = resolver.pool(*q.pool);
  job.calibration_sha256 = resolver.calibration ? resolver.calibration(q.task, method, q.profile) : std::nullopt;
  job.rotation_mode = q.rotation_mode;
  job.profile = q.profile;
  job.seed = q.seed;
  job.episodes = q.episodes;
  job.obs_noise = q.obs_noise;
  job.horizon = q.horizon;
  validate_job(job, q.source);
  return job;
}

namespace {

// `f()`, with a failure re-thrown as the experiment file's error at `field` (a resolver knows the
// name it was given, not which line of which file named it)
template <class F>
auto in_experiment(const Experiment& ex, const std::string& field, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    if (e.source() == ex.source) throw;
    throw InputError(ex.source, field, e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(ex.source, field, e.what());
  }
}

}  // namespace

Plan make_plan(const Experiment& ex, const PlanResolver& resolver) {
  if (!resolver.split || !resolver.backbone) throw std::invalid_argument("make_plan: resolver needs split and backbone");
  if (ex.pool && !resolver.pool) throw InputError(ex.source, "pool", "pools cannot be resolved here");
  check_job_count(ex);  // before anything is resolved or expanded
  Plan plan;
  plan.experiment = ex.name;
  plan.source = ex.source;
  plan.source_sha256 = ex.source_sha256;
  std::map<std::string, std::optional<PoolRef>> pools;  // by split
  for (const auto& split_name : ex.splits) {
    const auto it = ex.split_pools.find(split_name);
    const std::optional<std::string> name = it != ex.split_pools.end() ? it->second : ex.pool;
    if (name && !resolver.pool) throw InputError(ex.source, "pool", "pools cannot be resolved here");
    const std::string field = it != ex.split_pools.end() ? "pool." + split_name : "pool";
    pools[split_name] = name ? std::optional<PoolRef>(in_experiment(ex, field, [&] { return resolver.pool(*name); })) : std::nullopt;
  }
  const auto method_field = [](std::size_t i) { return "methods[" + std::to_string(i) + "]"; };
  std::vector<MethodEntry> methods = ex.methods;
  if (resolver.canonical_method)
    for (std::size_t i = 0; i < methods.size(); ++i)
      methods[i] = in_experiment(ex, method_field(i), [&] { return resolver.canonical_method(ex.methods[i]); });
  if (resolver.check_method)
    for (std::size_t i = 0; i < methods.size(); ++i)
      in_experiment(ex, method_field(i), [&] { resolver.check_method(methods[i]); });
  std::set<std::string> ids;
  for (std::size_t t = 0; t < ex.tasks.size(); ++t) {
    const std::string& task = ex.tasks[t];
    const std::string task_field = "tasks[" + std::to_string(t) + "]";
    in_experiment(ex, task_field, [&] { (void)sim::parse_task(task); });
    const BackboneRef backbone =
        in_experiment(ex, "backbone", [&] { return resolver.backbone(task, ex.backbone); });
    for (std::size_t s = 0; s < ex.splits.size(); ++s) {
      const std::string& split_name = ex.splits[s];
      const SplitRef split =
          in_experiment(ex, "splits[" + std::to_string(s) + "]", [&] { return resolver.split(task, split_name); });
      for (std::size_t m = 0; m < methods.size(); ++m) {
        const MethodEntry& method = methods[m];
        const std::optional<std::string> calibration =
            resolver.calibration
                ? in_experiment(ex, method_field(m), [&] { return resolver.calibration(task, method, ex.profile); })
                : std::nullopt;
        const std::string params = resolver.method_params
                                       ? in_experiment(ex, method_field(m), [&] { return resolver.method_params(method); })
                                       : method.params;
        const bool uses_pool =
            !resolver.method_uses_pool || in_experiment(ex, method_field(m), [&] { return resolver.method_uses_pool(method); });
        const std::optional<MethodPluginRef> plugin =
            resolver.method_plugin ? in_experiment(ex, method_field(m), [&] { return resolver.method_plugin(method); })
                                   : std::nullopt;
        for (const auto seed : ex.seeds) {
          PlannedJob pj;
          pj.index = static_cast<std::int64_t>(plan.jobs.size());
          pj.spec.task = task;
          pj.spec.split = split;
          pj.spec.method = method.name;
          pj.spec.method_params = params;
          pj.spec.method_plugin = plugin;
          pj.spec.backbone = backbone;
          if (uses_pool) pj.spec.pool = pools[split_name];
          pj.spec.calibration_sha256 = calibration;
          pj.spec.rotation_mode = ex.rotation_mode;
          pj.spec.profile = ex.profile;
          pj.spec.horizon = ex.horizon;
          pj.spec.seed = seed;
          pj.spec.episodes = ex.episodes;
          in_experiment(ex, task_field, [&] { validate_job(pj.spec, ex.source); });
          pj.job_id = job_id(pj.spec);
          if (!ids.insert(pj.job_id).second)
            throw InputError(ex.source, "", "two plan entries resolve to the same job " + pj.job_id);
          plan.jobs.push_back(std::move(pj));
        }
      }
    }
  }
  return plan;
}

}  // namespace actionshift::eval
