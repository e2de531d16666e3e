// The episode function of a job: names resolved and hashes checked against the spec, then the
// backbone through the method's adapter in the hidden-contract environment, one episode per call
#include "actionshift/eval/episode_fn.hpp"

#include "actionshift/adapt/identifier.hpp"
#include "actionshift/adapt/plugin.hpp"

#include "actionshift/adapt/registry.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/adapt/scale_corrector.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/policy/policy.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"
#include "actionshift/sim/robot_source.hpp"
#include "oracle_access.hpp"
#include "resolve_detail.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

namespace actionshift::eval {

namespace {

using detail::manifest_of_kind;
using detail::parse_params;

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

}  // namespace

namespace {

// the job's environment settings: its fidelity profile plus its observation noise (0: off) and horizon (0: the task's)
sim::EnvConfig env_config(const JobSpec& job) {
  sim::EnvConfig c = sim::profile_config(job.profile);
  c.obs_noise = job.obs_noise;
  c.horizon = job.horizon;
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
        adapt::method_rung(job.method) == adapt::Rung::oracle ? std::optional<sim::OracleRecorder>(detail::OracleAccess::view(env)) : std::nullopt;
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
