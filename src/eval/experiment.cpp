#include "actionshift/eval/experiment.hpp"

#include "actionshift/adapt/identifier.hpp"

#include "actionshift/adapt/plugin.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/adapt/scale_corrector.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/policy/policy.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"
#include "actionshift/sim/robot_source.hpp"
#include "oracle_access.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

namespace actionshift::eval {

namespace {

Manifest manifest_of_kind(const std::string& name, bool pool) {
  Manifest m = data::resolve_manifest(name);
  if (m.is_pool() != pool)
    throw InputError(name, "kind", pool ? "is a split manifest, not a pool" : "is a pool, not a split manifest");
  return m;
}

// The absolute path of a manifest named by a file ("" for a built-in name): recorded in the job, so
// the job is resolved from the same file wherever it runs, never by the manifest's name.
std::string manifest_file_path(const std::string& name_or_path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(name_or_path, ec)) return {};
  const std::filesystem::path abs = std::filesystem::absolute(name_or_path, ec);
  return ec ? std::string() : abs.lexically_normal().string();
}

// The manifest of a job's split or pool: the recorded file when the job has one, else the built-in
// manifest of that name. Its content hash is checked by the caller.
Manifest job_manifest(const std::string& name, const std::string& path, bool pool) {
  if (path.empty()) return manifest_of_kind(name, pool);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(path, pool ? "pool.path" : "split.path",
                     std::string("the ") + (pool ? "pool" : "split") + " manifest the job was made from is gone (not a regular file)");
  return manifest_of_kind(path, pool);
}

nlohmann::json parse_params(const std::string& text, const std::string& method) {
  const nlohmann::json j = parse_json_input(text, "method " + method, "params");
  if (!j.is_object()) throw InputError("method " + method, "params", "not a JSON object");
  return j;
}

}  // namespace

adapt::ResponseCalibration builtin_calibration(const std::string& task, const std::string& profile) {
  const auto text = data::builtin_calibration_text(task, profile);
  if (!text)
    throw InputError("calibration", task,
                     "no built-in calibration for this task on profile '" + profile + "' (run `actionshift calibrate --task " + task +
                         " --profile " + profile + "`)");
  return adapt::ResponseCalibration::from_json(std::string(*text), "builtin:calibration/" + profile + "/" + task);
}

adapt::ResponseCalibration builtin_selftest_calibration(const std::string& task, const std::string& profile) {
  const auto text = data::builtin_selftest_calibration_text(task, profile);
  if (!text)
    throw InputError("calibration", task, "no built-in self-test calibration for this task on profile '" + profile + "'");
  return adapt::ResponseCalibration::from_json(std::string(*text), "builtin:calibration/" + profile + "/selftest/" + task);
}

MethodEntry canonical_method(const MethodEntry& m) {
  const adapt::MethodLabel label = adapt::parse_method_label(m.name);
  MethodEntry out = m;  // an external method keeps its rung, version and files
  out.name = label.name;
  out.params = canonical_dump(adapt::merge_method_params(label, parse_params(m.params, label.name)));
  return out;
}

std::string resolved_method_params(const std::string& method, const std::string& params_json) {
  const MethodEntry m = canonical_method(MethodEntry{method, params_json});
  return canonical_dump(adapt::resolve_method_params(m.name, parse_params(m.params, m.name)));
}

std::string canonical_method_label(const std::string& label) {
  const MethodEntry m = canonical_method(MethodEntry{label, "{}"});
  const auto& known = adapt::method_names();
  if (std::find(known.begin(), known.end(), m.name) == known.end()) return label;  // not ours to canonicalize
  return adapt::method_variant_label(m.name, adapt::resolve_method_params(m.name, parse_params(m.params, m.name)));
}

namespace {
std::string method_variant_uncached(const JobSpec& job);
}  // namespace

std::string method_variant(const JobSpec& job) {
  // called for every record a job writes or re-reads: remember the last job's label (per thread)
  thread_local std::string last_method, last_params, last_label;
  if (job.method != last_method || job.method_params != last_params || last_label.empty()) {
    last_label = method_variant_uncached(job);
    last_method = job.method;
    last_params = job.method_params;
  }
  return last_label;
}

namespace {
std::string method_variant_uncached(const JobSpec& job) {
  const auto& known = adapt::method_names();
  const nlohmann::json params = parse_params(job.method_params, job.method);
  // a user method's label lists every parameter its job has, so it is the same whether or not the
  // method is registered in the process that reads its records
  if (!job.method_plugin && std::find(known.begin(), known.end(), job.method) != known.end())
    return adapt::method_variant_label(job.method, adapt::resolve_method_params(job.method, params));
  // a user method, or a method outside the registry (a test's stand-in): every parameter it has is part of its label
  std::string items;
  for (auto it = params.begin(); it != params.end(); ++it)
    items += (items.empty() ? "" : ",") + it.key() + "=" + (it.value().is_string() ? it.value().get<std::string>() : canonical_dump(it.value()));
  return items.empty() ? job.method : job.method + "{" + items + "}";
}
}  // namespace

std::optional<MethodPluginRef> method_plugin_ref(const std::string& method) {
  const auto id = adapt::method_plugin_identity(method);
  if (!id) return std::nullopt;
  return MethodPluginRef{id->kind, id->version, id->rung, id->sha256, id->files};
}

PlanResolver default_resolver() {
  PlanResolver r;
  r.split = [](const std::string&, const std::string& split) {
    const Manifest m = manifest_of_kind(split, false);
    return SplitRef{m.name(), m.manifest_sha256(), static_cast<std::int64_t>(m.test().size()), manifest_file_path(split)};
  };
  r.pool = [](const std::string& pool) {
    const Manifest m = manifest_of_kind(pool, true);
    return PoolRef{m.name(), m.pool_sha256(), manifest_file_path(pool)};
  };
  r.backbone = [](const std::string& task, const std::string& name) {
    // identity only: an external policy's process is started by the job, not by planning it
    const policy::BackboneIdentity b = policy::backbone_identity(name, sim::parse_task(task));
    return BackboneRef{b.name, b.sha256};
  };
  r.calibration = [](const std::string& task, const MethodEntry& m, const std::string& profile) -> std::optional<std::string> {
    if (!adapt::method_needs_calibration(m.name)) return std::nullopt;
    return builtin_calibration(task, profile).sha256();
  };
  r.canonical_method = [](const MethodEntry& m) { return canonical_method(m); };
  r.check_method = [](const MethodEntry& m) { adapt::resolve_method_params(m.name, parse_params(m.params, m.name)); };
  r.method_params = [](const MethodEntry& m) { return resolved_method_params(m.name, m.params); };
  r.method_uses_pool = [](const MethodEntry& m) { return adapt::method_needs_pool(m.name); };
  r.method_plugin = [](const MethodEntry& m) { return method_plugin_ref(m.name); };
  return r;
}

namespace {

// the job's environment settings: its fidelity profile plus its observation noise (0: off)
sim::EnvConfig env_config(const JobSpec& job) {
  sim::EnvConfig c = sim::profile_config(job.profile);
  c.obs_noise = job.obs_noise;
  return c;
}

struct Worker {
  std::unique_ptr<policy::Policy> policy;
  std::map<std::int64_t, sim::HiddenContractEnv> envs;  // by contract index
};

struct Context {
  JobSpec job;
  std::shared_ptr<const sim::EnvModel> model;
  std::vector<Contract> contracts;
  std::vector<Contract> pool;
  std::optional<adapt::ResponseModel> response;
  adapt::TcpSlice slice;
  int finger_start{-1};  // the finger channel's offset, when the calibration has one
  std::shared_ptr<const policy::Policy> prototype;
  nlohmann::json params;
  sim::FrameRotation rotation{sim::FrameRotation::kLive};
  EpisodeHooks hooks;  // default: the runner's episodes, unobserved

  std::mutex mutex;
  std::map<unsigned, std::unique_ptr<Worker>> workers;

  Worker& worker(unsigned index) {
    std::lock_guard<std::mutex> lock(mutex);
    auto& w = workers[index];
    if (!w) {
      w = std::make_unique<Worker>();
      w->policy = prototype->clone();
    }
    return *w;
  }

  EpisodeRecord run(const EpisodeTask& t) {
    Worker& w = worker(t.worker);
    const auto ci = static_cast<std::size_t>(t.contract_index);
    const Contract& truth = hooks.contract_override ? *hooks.contract_override : contracts.at(ci);
    auto it = w.envs.find(t.contract_index);
    if (it == w.envs.end()) it = w.envs.emplace(t.contract_index, sim::HiddenContractEnv(model, truth, rotation)).first;
    sim::HiddenContractEnv& env = it->second;

    adapt::MethodInputs in;
    // the only privileged path: the oracle's view, which only the runner can construct
    const std::optional<sim::OracleRecorder> oracle =
        job.method == "oracle" ? std::optional<sim::OracleRecorder>(detail::OracleAccess::view(env)) : std::nullopt;
    if (oracle) in.truth = &oracle->contract();
    if (!pool.empty()) in.pool = &pool;
    if (response) in.model = &*response;
    in.task = job.task;
    in.gain_fit = &adapt::fit_window_gain;  // the scale corrector's least-squares fit by Ceres (ActionShift::fit)
    const auto adapter = adapt::make_adapter(job.method, params, in);

    Eigen::VectorXd obs = env.reset(t.episode_seed);
    w.policy->reset();
    adapter->begin_episode(t.adapter_seed);  // never the environment's seed: it names the contract
    EpisodeRecord rec;
    rec.contract_sha256 = truth.sha256();
    const sim::OracleRecorder view = detail::OracleAccess::view(env);
    auto show = [&](int step, bool probe, const Action* raw) {
      if (hooks.observer) hooks.observer(EpisodeStepView{step, env.horizon(), probe, &env.last(), &view.env(), raw});
    };
    show(0, false, nullptr);
    for (int step = 0; step < env.horizon(); ++step) {
      const Action intent = w.policy->act(obs);
      const Mat3 R = rotation == sim::FrameRotation::kIdentity ? Mat3::Identity() : adapt::tcp_rotation(obs, slice);
      const Action raw = adapter->encode(intent, R);
      const bool probe = adapter->last_step().probe;
      const sim::StepResult& r = env.step(raw);
      show(step + 1, probe, &raw);
      if (r.safety != sim::SafetyFlag::kNone) break;  // the episode ended by a safety check
      const Pose6 response_now = adapt::tcp_response(obs, r.obs, slice);
      if (probe) {
        ++rec.probe_steps;
        rec.probe_displacement += response_now.head<3>().norm();
      }
      if (finger_start >= 0) {
        const auto f = static_cast<Eigen::Index>(finger_start);
        adapter->observe_fingers(0.5 * (r.obs[f] + r.obs[f + 1]) - 0.5 * (obs[f] + obs[f + 1]));
      }
      adapter->observe(raw, response_now, R);
      obs = r.obs;
      if (r.episode_over()) break;
    }
    const sim::EpisodeStats& st = env.episode();
    rec.success_once = st.success_once;
    rec.success_at_end = st.success_at_end;
    rec.task_return = st.episode_return;
    rec.steps = st.steps;
    if (st.safety != sim::SafetyFlag::kNone) rec.safety_flags.emplace_back(sim::safety_flag_name(st.safety));
    return rec;
  }
};

}  // namespace

namespace {
EpisodeFn build_episode_fn(const JobSpec& job, std::shared_ptr<const policy::Policy> backbone, EpisodeHooks hooks,
                           const std::optional<adapt::ResponseCalibration>& given_calibration,
                           const std::string& calibration_source = "calibration");
}  // namespace

void check_method_plugin(const JobSpec& job) {
  const std::optional<MethodPluginRef> now = method_plugin_ref(job.method);
  if (!job.method_plugin) {
    if (now)
      throw InputError("job", "method.plugin",
                       "names no user method, but '" + job.method + "' is one registered here; make the job again");
    return;
  }
  const MethodPluginRef& want = *job.method_plugin;
  if (!now)
    throw InputError("job", "method.name",
                     "'" + job.method + "' is a user method (" + want.kind + ", version " + want.version +
                         ") that is not registered in this process; register it before running its job (docs/methods.md)");
  if (now->sha256 != want.sha256)
    throw InputError(want.files.empty() ? "job" : want.files.front(), "method.plugin.sha256",
                     "user method '" + job.method + "' is now version " + now->version + " (" + now->kind + ", rung " + now->rung +
                         ", content " + now->sha256.substr(0, 12) + "), the job's version " + want.version + " (" + want.kind +
                         ", rung " + want.rung + ", content " + want.sha256.substr(0, 12) + "); make the job again");
}

EpisodeFn make_episode_fn(const JobSpec& job, const EpisodeFnOptions& options) { return make_episode_fn(job, options, EpisodeHooks{}); }

EpisodeFn make_episode_fn(const JobSpec& job, const EpisodeFnOptions& options, EpisodeHooks hooks) {
  validate_job(job);
  policy::RegistryOptions registry;
  registry.external = options.external;
  return build_episode_fn(job, std::shared_ptr<const policy::Policy>(policy::make_policy(job.backbone.name, sim::parse_task(job.task), registry)),
                          std::move(hooks), options.calibration, options.calibration_source);
}

namespace {

EpisodeFn build_episode_fn(const JobSpec& job, std::shared_ptr<const policy::Policy> backbone, EpisodeHooks hooks,
                           const std::optional<adapt::ResponseCalibration>& given_calibration,
                           const std::string& calibration_source) {
  validate_job(job);
  if (!backbone) throw InputError("job", "backbone", "no backbone given");
  auto ctx = std::make_shared<Context>();
  ctx->job = job;
  ctx->hooks = std::move(hooks);
  const sim::TaskId task = sim::parse_task(job.task);
  if (job.policy_files) {
    const std::string now = files_content_sha256(job.policy_files->paths, "policy_files");
    if (now != job.policy_files->sha256)
      throw InputError(job.policy_files->paths.front(), "policy_files.sha256",
                       "the policy files changed since the job was made (their hash is " + now + ", the job's " +
                           job.policy_files->sha256 + "); make the job again");
  }
  if (job.robot) {
    const sim::RobotSource robot = sim::load_robot_source(job.robot->urdf, job.robot->packages);
    if (robot.sha256 != job.robot->sha256)
      throw InputError(job.robot->urdf, "robot.sha256",
                       "the description (URDF or a mesh) changed since the job was made: its hash is " + robot.sha256 +
                           ", the job's " + job.robot->sha256);
    ctx->model = sim::EnvModel::make(task, env_config(job), robot.description);
  } else {
    ctx->model = sim::EnvModel::make(task, env_config(job));
  }
  ctx->slice = tcp_slice(ctx->model->layout());
  ctx->rotation = parse_rotation_mode(job.rotation_mode, "job", "rotation_mode");

  // a split's identity is its content hash: the job's file when it names one, else the built-in name
  const std::string split_source = job.split.path.empty() ? job.split.name : job.split.path;
  const Manifest split = job_manifest(job.split.name, job.split.path, false);
  if (split.manifest_sha256() != job.split.sha256)
    throw InputError(split_source, "manifest_sha256", "is " + split.manifest_sha256() + " but the job was planned with " + job.split.sha256);
  ctx->contracts = split.contracts();
  if (static_cast<std::int64_t>(ctx->contracts.size()) != job.split.contracts)
    throw InputError(split_source, "test", "holds a different number of contracts than the job");

  if (job.pool) {
    const std::string pool_source = job.pool->path.empty() ? job.pool->name : job.pool->path;
    const Manifest pool = job_manifest(job.pool->name, job.pool->path, true);
    if (pool.pool_sha256() != job.pool->sha256)
      throw InputError(pool_source, "pool_sha256", "is " + pool.pool_sha256() + " but the job was planned with " + job.pool->sha256);
    ctx->pool = pool.contracts();
  } else if (adapt::method_needs_pool(job.method)) {
    throw InputError("job", "pool", "method '" + job.method + "' needs a pool (--pool reference9|full|FILE)");
  }
  if (adapt::method_needs_calibration(job.method)) {
    const auto cal = given_calibration ? *given_calibration : builtin_calibration(job.task, job.profile);
    if (!job.calibration_sha256 || *job.calibration_sha256 != cal.sha256())
      throw InputError("job", "calibration_sha256",
                       given_calibration ? "does not match the given calibration file (" + cal.sha256() + ")"
                                         : "does not match the built-in calibration of " + job.task + " on profile " + job.profile +
                                               " (" + cal.sha256() + ")");
    if (given_calibration && cal.task != job.task)
      throw InputError(calibration_source, "task", "is " + cal.task + ", not the job's " + job.task);
    const std::string cal_source = given_calibration ? calibration_source : "built-in calibration " + job.task;
    check_calibration_layout(cal, ctx->model->layout(), job.task, cal_source);
    ctx->response = cal.model();
    if (cal.gripper) ctx->finger_start = cal.gripper->start;
  }
  if (backbone->name() != job.backbone.name)
    throw InputError("backbone " + backbone->name(), "name", "is not the job's backbone " + job.backbone.name);
  if (backbone->task() != task)
    throw InputError("backbone " + backbone->name(), "task", "acts on " + std::string(sim::task_name(backbone->task())) + ", not " + job.task);
  ctx->prototype = std::move(backbone);
  if (ctx->prototype->sha256() != job.backbone.sha256)
    throw InputError("backbone " + job.backbone.name, "sha256", "is " + ctx->prototype->sha256() + " but the job was planned with " + job.backbone.sha256);
  check_method_plugin(job);
  ctx->params = adapt::resolve_method_params(job.method, parse_params(job.method_params, job.method));
  // parameters that need the calibration, and missing or corrupt identifier weights, fail here, before any episode
  if (job.method == "grammar_belief" || adapt::parse_identifier_kind(job.method)) {
    adapt::MethodInputs in;
    in.model = ctx->response ? &*ctx->response : nullptr;
    adapt::make_adapter(job.method, ctx->params, in);
  }
  return [ctx](const EpisodeTask& t) { return ctx->run(t); };
}

}  // namespace

EpisodeFn make_episode_fn(const JobSpec& job, std::shared_ptr<const policy::Policy> backbone, EpisodeHooks hooks) {
  return build_episode_fn(job, std::move(backbone), std::move(hooks), std::nullopt);
}

EpisodeFn make_episode_fn(const JobSpec& job, std::shared_ptr<const policy::Policy> backbone, const EpisodeFnOptions& options,
                          EpisodeHooks hooks) {
  return build_episode_fn(job, std::move(backbone), std::move(hooks), options.calibration, options.calibration_source);
}

}  // namespace actionshift::eval
