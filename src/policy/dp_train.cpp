// Diffusion Policy: demonstrations from the scripted expert and the training loop (dp.hpp)
#include "actionshift/policy/dp.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/workers.hpp"
#include "actionshift/policy/expert.hpp"
#include "actionshift/sim/env.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
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

}  // namespace

void check_train_dp_options(const TrainDpOptions& o) {
  if (o.demos <= 0) throw InputError("", "demos", "must be positive");
  if (o.iterations <= 0) throw InputError("", "iterations", "must be positive");
  if (o.batch_size <= 0) throw InputError("", "batch", "must be positive");
  if (o.log_every <= 0) throw InputError("", "log-every", "must be positive");
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

TrainDpResult train_dp(const TrainDpOptions& o, const std::function<void(const TrainDpProgress&)>& progress) {
  check_train_dp_options(o);
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
  for (int it = 1; it <= o.iterations; ++it) {
    for (int b = 0; b < o.batch_size; ++b)
      window(static_cast<std::size_t>(batch_rng.uniform_int(windows.size())), chunks[static_cast<std::size_t>(b)], conds[static_cast<std::size_t>(b)]);
    loss_sum += learner.step(chunks, conds, threads);
    ++loss_n;
    if (it % o.log_every == 0 || it == o.iterations) {
      result.final_loss = loss_sum / loss_n;
      if (progress) progress({it, result.final_loss, elapsed()});
      loss_sum = 0.0;
      loss_n = 0;
    }
  }
  result.train_seconds = elapsed() - result.collect_seconds;
  w.params = learner.ema();
  result.weights = std::move(w);
  return result;
}

}  // namespace actionshift::policy
