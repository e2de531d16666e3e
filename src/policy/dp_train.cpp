// Diffusion Policy: demonstrations from the scripted expert and the training loop (dp.hpp)
#include "actionshift/policy/dp.hpp"

#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/weight_file.hpp"
#include "actionshift/core/workers.hpp"
#include "actionshift/policy/expert.hpp"
#include "actionshift/sim/env.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace actionshift::policy {
namespace {

constexpr std::uint64_t kDemoStream = 0x6470'6465'6d6f'0000ULL;   // "dpdemo"
constexpr std::uint64_t kBatchStream = 0x6470'6261'7463'6800ULL;  // "dpbatch"
constexpr float kStdFloor = 1e-2f;

struct Demo {
  std::vector<Eigen::VectorXd> obs;
  std::vector<Action> actions;
  bool success{false};
};

// Eigen blocks the depth of a matrix product by a length it derives from the L1 data cache size
// (kDpEigenL1Bytes in dp.hpp): train_dp fixes it to 32 KiB while it runs, as DpPolicy does for
// sampling. configs/backbones/pick_cube.dp.asdp was trained under 32 KiB (its curve's first loss,
// iteration 50, is reproduced to the last bit with 32 KiB and differs in the ninth digit with 48 KiB).
struct EigenL1Pin {
  std::ptrdiff_t l1{Eigen::l1CacheSize()}, l2{Eigen::l2CacheSize()}, l3{Eigen::l3CacheSize()};
  EigenL1Pin() { Eigen::setCpuCacheSizes(kDpEigenL1Bytes, l2, l3); }
  ~EigenL1Pin() { Eigen::setCpuCacheSizes(l1, l2, l3); }
  EigenL1Pin(const EigenL1Pin&) = delete;
  EigenL1Pin& operator=(const EigenL1Pin&) = delete;
};

// ---- checkpoints: the learner's state, the batch sampler's position, the curve so far
constexpr std::string_view kCheckpointMagic{"ASDPCKP\0", 8};
constexpr std::uint32_t kCheckpointVersion = 1;

// What decides the trained bytes (not threads, progress or the checkpoint itself): a checkpoint
// continues only the run of the same settings.
std::string settings_sha256(const TrainDpOptions& o) {
  const DpLearnOptions& l = o.learn;
  const nlohmann::json j = {{"task", std::string(sim::task_name(o.task))}, {"profile", o.profile}, {"seed", o.seed},
                            {"down_dims", o.down_dims}, {"demos", o.demos}, {"iterations", o.iterations},
                            {"batch_size", o.batch_size}, {"ddim_steps", o.ddim_steps}, {"log_every", o.log_every},
                            {"learn", {l.learning_rate, l.beta1, l.beta2, l.eps, l.weight_decay, l.warmup_steps, l.ema_max_decay, l.shards}}};
  return sha256_hex(j.dump());
}

struct Checkpoint {
  DpLearner::State state;
  double loss_sum{0.0};
  int loss_n{0};
  double train_seconds{0.0};
  std::vector<TrainDpProgress> curve;
};

void write_checkpoint(const std::string& path, const std::string& settings, const Checkpoint& c) {
  std::string payload;
  for (const auto* v : {&c.state.params, &c.state.m, &c.state.v, &c.state.ema})
    payload.append(reinterpret_cast<const char*>(v->data()), v->size() * sizeof(float));
  nlohmann::json curve = nlohmann::json::array();
  for (const auto& p : c.curve) curve.push_back({p.iteration, p.loss, p.seconds});
  const nlohmann::json header = {{"format", "actionshift-dp-checkpoint"}, {"settings_sha256", settings},
                                 {"iteration", c.state.steps},            {"parameters", c.state.params.size()},
                                 {"loss_sum", c.loss_sum},                {"loss_n", c.loss_n},
                                 {"train_seconds", c.train_seconds},      {"curve", curve},
                                 {"payload_sha256", sha256_hex(payload)}};
  write_file_atomic(path, weight_file::frame(kCheckpointMagic, kCheckpointVersion, header, payload));
}

Checkpoint read_checkpoint(const std::string& path, const std::string& settings, std::size_t parameters, int iterations) {
  const std::string bytes = weight_file::read(path, std::uintmax_t{4} << 30, "Diffusion Policy checkpoint");
  const weight_file::Unframed u = weight_file::unframe(bytes, kCheckpointMagic, kCheckpointVersion, path, "Diffusion Policy checkpoint");
  const nlohmann::json& h = u.header;
  try {
    if (h.at("settings_sha256").get<std::string>() != settings)
      throw InputError(path, "settings_sha256",
                       "written by a train dp run with other settings (task, seed, demos, iterations, network or optimiser); "
                       "delete it or give another --checkpoint");
    if (h.at("parameters").get<std::size_t>() != parameters) throw InputError(path, "parameters", "not this network's parameter count");
    weight_file::check_payload(u, 4 * static_cast<std::int64_t>(parameters), path, true);
    Checkpoint c;
    c.state.steps = h.at("iteration").get<int>();
    if (c.state.steps < 0 || c.state.steps > iterations) throw InputError(path, "iteration", "outside this run's iterations");
    c.loss_sum = h.at("loss_sum").get<double>();
    c.loss_n = h.at("loss_n").get<int>();
    c.train_seconds = h.at("train_seconds").get<double>();
    for (const auto& p : h.at("curve")) c.curve.push_back({p.at(0).get<int>(), p.at(1).get<double>(), p.at(2).get<double>()});
    const auto* f = reinterpret_cast<const float*>(u.payload.data());
    for (auto* v : {&c.state.params, &c.state.m, &c.state.v, &c.state.ema}) {
      v->assign(f, f + parameters);
      f += parameters;
    }
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, "header", std::string("malformed checkpoint header: ") + e.what());
  }
}

}  // namespace

void check_train_dp_options(const TrainDpOptions& o) {
  if (o.demos <= 0) throw InputError("", "demos", "must be positive");
  if (o.iterations <= 0) throw InputError("", "iterations", "must be positive");
  if (o.batch_size <= 0) throw InputError("", "batch", "must be positive");
  if (o.log_every <= 0) throw InputError("", "log-every", "must be positive");
  if (o.checkpoint_every <= 0) throw InputError("", "checkpoint-every", "must be positive");
  if (!(o.learn.learning_rate > 0) || !std::isfinite(o.learn.learning_rate)) throw InputError("", "lr", "must be positive");
  try {
    (void)sim::profile_config(o.profile);
  } catch (const std::invalid_argument& e) {
    throw InputError("", "profile", e.what());
  }
  DpArch arch;
  arch.obs_dim = sim::observation_layout(o.task).size();
  arch.down_dims = o.down_dims;
  try {
    arch.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError("", "down-dims", e.what());
  }
  if (o.ddim_steps < 0 || o.ddim_steps > arch.diffusion_steps)
    throw InputError("", "ddim-steps", "must be in [0, " + std::to_string(arch.diffusion_steps) + "] (0: DDPM)");
}

int check_train_dp_checkpoint(const TrainDpOptions& o) {
  check_train_dp_options(o);
  if (o.checkpoint.empty() || !std::filesystem::exists(o.checkpoint)) return 0;
  DpArch arch;
  arch.obs_dim = sim::observation_layout(o.task).size();
  arch.down_dims = o.down_dims;
  return read_checkpoint(o.checkpoint, settings_sha256(o), static_cast<std::size_t>(dp_parameter_count(arch)), o.iterations).state.steps;
}

TrainDpResult train_dp(const TrainDpOptions& o, const std::function<void(const TrainDpProgress&)>& progress) {
  check_train_dp_options(o);
  const EigenL1Pin pin;
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  DpArch arch;
  arch.obs_dim = sim::observation_layout(o.task).size();
  arch.down_dims = o.down_dims;
  const unsigned threads = resolve_threads(o.threads);

  // demonstrations, in parallel, stored by episode index
  auto model = sim::EnvModel::make(o.task, sim::profile_config(o.profile));
  std::vector<Demo> demos(static_cast<std::size_t>(o.demos));
  std::atomic<int> next{0};
  run_workers(std::min(threads, static_cast<unsigned>(o.demos)), [&](unsigned) {
    sim::Env env(model);
    for (int k = next.fetch_add(1); k < o.demos; k = next.fetch_add(1)) {
      Demo& d = demos[static_cast<std::size_t>(k)];
      auto expert = make_expert(o.task);
      expert->reset();
      Eigen::VectorXd obs = env.reset(derive_seed({o.seed, kDemoStream, static_cast<std::uint64_t>(k)}));
      while (true) {
        const Action a = expert->act(obs).cwiseMax(-1.0).cwiseMin(1.0);
        d.obs.push_back(obs);
        d.actions.push_back(a);
        const sim::StepResult& r = env.step(a);
        obs = r.obs;
        if (r.episode_over()) break;
      }
      d.success = env.episode().success_once;
    }
  });
  TrainDpResult result;
  result.demos = o.demos;
  std::vector<const Demo*> kept;
  for (const Demo& d : demos)
    if (d.success) kept.push_back(&d);
  result.demo_successes = static_cast<int>(kept.size());
  if (kept.empty()) throw std::runtime_error("train_dp: no expert demonstration succeeded");

  // observation normalisation over every kept frame
  const int od = arch.obs_dim;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(od), sq = Eigen::VectorXd::Zero(od);
  std::int64_t frames = 0;
  for (const Demo* d : kept)
    for (const auto& x : d->obs) {
      sum += x;
      sq += x.cwiseProduct(x);
      ++frames;
    }
  const Eigen::VectorXd mean = sum / static_cast<double>(frames);
  const Eigen::VectorXd var = (sq / static_cast<double>(frames) - mean.cwiseProduct(mean)).cwiseMax(0.0);
  DpWeights w;
  w.task = o.task;
  w.arch = arch;
  w.ddim_steps = o.ddim_steps;
  w.obs_mean = mean.cast<float>();
  w.obs_std = var.cwiseSqrt().cast<float>().cwiseMax(kStdFloor);

  // training windows (demo, start)
  std::vector<std::pair<int, int>> windows;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const int L = static_cast<int>(kept[i]->actions.size());
    for (int s = -(arch.obs_horizon - 1); s < L - arch.pred_horizon + arch.act_horizon - 1; ++s) windows.emplace_back(static_cast<int>(i), s);
  }
  if (windows.empty()) throw std::runtime_error("train_dp: demonstrations too short for the prediction horizon");
  result.windows = static_cast<std::int64_t>(windows.size());
  result.collect_seconds = elapsed();
  auto window = [&](std::size_t idx, DpMat<float>& chunk, DpVec<float>& cond) {
    const Demo& d = *kept[static_cast<std::size_t>(windows[idx].first)];
    const int s = windows[idx].second;
    const int L = static_cast<int>(d.actions.size());
    cond.resize(arch.obs_horizon * od);
    for (int j = 0; j < arch.obs_horizon; ++j) {
      const Eigen::VectorXd& x = d.obs[static_cast<std::size_t>(std::clamp(s + j, 0, L - 1))];
      cond.segment(j * od, od) = (x.cast<float>() - w.obs_mean).cwiseQuotient(w.obs_std);
    }
    chunk.resize(arch.action_dim, arch.pred_horizon);
    for (int j = 0; j < arch.pred_horizon; ++j) {
      const int t = s + j;
      Action a;
      if (t < L) {
        a = d.actions[static_cast<std::size_t>(std::max(t, 0))];
      } else {
        a.setZero();
        a(kGripper) = d.actions.back()(kGripper);
      }
      chunk.col(j) = a.cast<float>();
    }
  };

  DpLearnOptions lo = o.learn;
  lo.total_steps = o.iterations;
  DpLearner learner(arch, lo, derive_seed({o.seed, kBatchStream, 0x1111}));
  Rng batch_rng(derive_seed({o.seed, kBatchStream}));
  std::vector<DpMat<float>> chunks(static_cast<std::size_t>(o.batch_size));
  std::vector<DpVec<float>> conds(static_cast<std::size_t>(o.batch_size));
  double loss_sum = 0.0;
  int loss_n = 0;
  double seconds_before = 0.0;  // training time of the runs before a resume
  const std::string settings = o.checkpoint.empty() ? std::string() : settings_sha256(o);
  if (!o.checkpoint.empty() && std::filesystem::exists(o.checkpoint)) {
    Checkpoint c = read_checkpoint(o.checkpoint, settings, learner.params().size(), o.iterations);
    // the sampler's position: the same draws as the iterations already done (a few per iteration)
    for (int it = 0; it < c.state.steps; ++it)
      for (int b = 0; b < o.batch_size; ++b) (void)batch_rng.uniform_int(windows.size());
    result.resumed_at = c.state.steps;
    loss_sum = c.loss_sum;
    loss_n = c.loss_n;
    seconds_before = c.train_seconds;
    result.curve = std::move(c.curve);
    if (!result.curve.empty()) result.final_loss = result.curve.back().loss;
    learner.restore(std::move(c.state));
  }
  const double train_start = elapsed();
  auto train_seconds = [&] { return seconds_before + elapsed() - train_start; };
  for (int it = result.resumed_at + 1; it <= o.iterations; ++it) {
    for (int b = 0; b < o.batch_size; ++b)
      window(static_cast<std::size_t>(batch_rng.uniform_int(windows.size())), chunks[static_cast<std::size_t>(b)], conds[static_cast<std::size_t>(b)]);
    loss_sum += learner.step(chunks, conds, threads);
    ++loss_n;
    if (it % o.log_every == 0 || it == o.iterations) {
      result.final_loss = loss_sum / loss_n;
      const TrainDpProgress p{it, result.final_loss, result.collect_seconds + train_seconds()};
      result.curve.push_back(p);
      if (progress) progress(p);
      loss_sum = 0.0;
      loss_n = 0;
    }
    if (!o.checkpoint.empty() && it % o.checkpoint_every == 0 && it < o.iterations)
      write_checkpoint(o.checkpoint, settings, {learner.state(), loss_sum, loss_n, train_seconds(), result.curve});
  }
  result.train_seconds = train_seconds();
  w.params = learner.ema();
  result.weights = std::move(w);
  return result;
}

}  // namespace actionshift::policy
