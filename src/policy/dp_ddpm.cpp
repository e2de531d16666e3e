// Diffusion Policy: DDPM schedule, samplers, and the AdamW + EMA trainer step (dp.hpp)
#include "actionshift/policy/dp.hpp"

#include "actionshift/core/workers.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace actionshift::policy {
namespace {

constexpr std::uint64_t kDpNoiseStream = 0x6470'6e6f'6973'6500ULL;  // "dpnoise": keeps training noise apart

DpMat<float> normal_mat(Rng& rng, int rows, int cols) {
  DpMat<float> m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m(i) = static_cast<float>(rng.normal());
  return m;
}

}  // namespace

DdpmSchedule DdpmSchedule::squaredcos_cap_v2(int steps) {
  if (steps <= 0) throw std::invalid_argument("DdpmSchedule: steps must be positive");
  auto alpha_bar = [](double t) {
    const double c = std::cos((t + 0.008) / 1.008 * std::numbers::pi / 2);
    return c * c;
  };
  DdpmSchedule s;
  double prod = 1.0;
  for (int i = 0; i < steps; ++i) {
    const double b = std::min(1.0 - alpha_bar(static_cast<double>(i + 1) / steps) / alpha_bar(static_cast<double>(i) / steps), 0.999);
    s.betas.push_back(b);
    prod *= 1.0 - b;
    s.alphas_cumprod.push_back(prod);
  }
  return s;
}

DpMat<float> ddpm_step(const DdpmSchedule& s, int t, const DpMat<float>& x, const DpMat<float>& eps, const DpMat<float>& noise, bool clip) {
  if (t < 0 || t >= s.steps()) throw std::invalid_argument("ddpm_step: step out of range");
  const double a_t = s.alphas_cumprod[static_cast<std::size_t>(t)];
  const double a_prev = t > 0 ? s.alphas_cumprod[static_cast<std::size_t>(t - 1)] : 1.0;
  const double b_t = 1.0 - a_t, b_prev = 1.0 - a_prev;
  const double cur_alpha = a_t / a_prev, cur_beta = 1.0 - cur_alpha;
  DpMat<float> x0 = ((x.cast<double>() - std::sqrt(b_t) * eps.cast<double>()) / std::sqrt(a_t)).cast<float>();
  if (clip) x0 = x0.cwiseMax(-1.0f).cwiseMin(1.0f);
  const double c0 = std::sqrt(a_prev) * cur_beta / b_t;
  const double ct = std::sqrt(cur_alpha) * b_prev / b_t;
  DpMat<float> prev = (c0 * x0.cast<double>() + ct * x.cast<double>()).cast<float>();
  if (t > 0) {
    const double var = std::max(b_prev / b_t * cur_beta, 1e-20);
    prev += static_cast<float>(std::sqrt(var)) * noise;
  }
  return prev;
}

DpMat<float> dp_sample(const DpUnet<float>& net, const float* params, const DdpmSchedule& schedule, const DpVec<float>& cond, Rng& rng,
                       DpUnet<float>::Workspace& ws, int ddim_steps) {
  const DpArch& a = net.arch();
  const int T = schedule.steps();
  if (ddim_steps < 0 || ddim_steps > T) throw std::invalid_argument("dp_sample: ddim_steps must be in [0, diffusion steps]");
  DpMat<float> x = normal_mat(rng, a.action_dim, a.pred_horizon);
  if (ddim_steps == 0) {
    const DpMat<float> zero = DpMat<float>::Zero(a.action_dim, a.pred_horizon);
    for (int t = T - 1; t >= 0; --t) {
      const DpMat<float> eps = net.forward(params, x, t, cond, ws);
      x = ddpm_step(schedule, t, x, eps, t > 0 ? normal_mat(rng, a.action_dim, a.pred_horizon) : zero);
    }
    return x;
  }
  // DDIM, eta = 0, "leading" timesteps (i * T/n), clip_sample, set_alpha_to_one
  const int ratio = T / ddim_steps;
  for (int i = ddim_steps - 1; i >= 0; --i) {
    const int t = i * ratio;
    const DpMat<float> eps = net.forward(params, x, t, cond, ws);
    const double a_t = schedule.alphas_cumprod[static_cast<std::size_t>(t)];
    const double a_prev = t - ratio >= 0 ? schedule.alphas_cumprod[static_cast<std::size_t>(t - ratio)] : 1.0;
    const Eigen::MatrixXd x0 = ((x.cast<double>() - std::sqrt(1.0 - a_t) * eps.cast<double>()) / std::sqrt(a_t)).cwiseMax(-1.0).cwiseMin(1.0);
    x = (std::sqrt(a_prev) * x0 + std::sqrt(1.0 - a_prev) * eps.cast<double>()).cast<float>();
  }
  return x;
}

DpLearner::DpLearner(const DpArch& arch, const DpLearnOptions& options, std::uint64_t seed)
    : net_(arch), o_(options), seed_(seed), schedule_(DdpmSchedule::squaredcos_cap_v2(arch.diffusion_steps)) {
  if (!(o_.learning_rate > 0) || o_.shards <= 0 || o_.warmup_steps < 0 || o_.total_steps < 0 || !(o_.ema_max_decay >= 0 && o_.ema_max_decay < 1))
    throw std::invalid_argument("DpLearner: learning rate and shards must be positive, ema_max_decay in [0, 1)");
  params_ = net_.init(seed);
  m_.assign(params_.size(), 0.0f);
  v_.assign(params_.size(), 0.0f);
  ema_ = params_;
}

void DpLearner::restore(State state) {
  const std::size_t P = params_.size();
  if (state.steps < 0 || state.params.size() != P || state.m.size() != P || state.v.size() != P || state.ema.size() != P)
    throw std::invalid_argument("DpLearner::restore: the state is not of this network (" + std::to_string(P) + " parameters)");
  t_ = state.steps;
  params_ = std::move(state.params);
  m_ = std::move(state.m);
  v_ = std::move(state.v);
  ema_ = std::move(state.ema);
}

double DpLearner::learning_rate(int n) const {
  // diffusers' get_cosine_schedule_with_warmup (the scheduler's counter is n - 1 at optimiser step n)
  const double s = n - 1;
  if (s < o_.warmup_steps) return o_.learning_rate * s / std::max(1, o_.warmup_steps);
  if (o_.total_steps <= 0) return o_.learning_rate;
  const double progress = (s - o_.warmup_steps) / std::max(1, o_.total_steps - o_.warmup_steps);
  return o_.learning_rate * std::max(0.0, 0.5 * (1.0 + std::cos(std::numbers::pi * progress)));
}

double DpLearner::ema_decay(int n) const {
  const double s = n - 1;
  if (s <= 0) return 0.0;
  return std::min(o_.ema_max_decay, (1.0 + s) / (10.0 + s));
}

double DpLearner::step(const std::vector<DpMat<float>>& actions, const std::vector<DpVec<float>>& conds, unsigned threads) {
  const DpArch& a = net_.arch();
  const int B = static_cast<int>(actions.size());
  if (B == 0 || conds.size() != actions.size()) throw std::invalid_argument("DpLearner::step: needs a non-empty batch with one condition per chunk");
  for (int k = 0; k < B; ++k) {
    const auto sk = static_cast<std::size_t>(k);
    if (actions[sk].rows() != a.action_dim || actions[sk].cols() != a.pred_horizon || conds[sk].size() != a.obs_horizon * a.obs_dim)
      throw std::invalid_argument("DpLearner::step: sample " + std::to_string(k) + " has the wrong shape");
  }
  const int n_shards = std::min(o_.shards, B);
  const auto P = static_cast<std::size_t>(net_.parameter_count());
  std::vector<std::vector<float>>& grads = grads_;  // kept between steps: no fresh pages every step
  grads.resize(static_cast<std::size_t>(n_shards));
  std::vector<double> losses(static_cast<std::size_t>(B));
  const float scale = 2.0f / static_cast<float>(static_cast<double>(B) * a.action_dim * a.pred_horizon);
  const int T = schedule_.steps();
  auto shard_begin = [&](int s) { return static_cast<int>(static_cast<std::int64_t>(B) * s / n_shards); };
  // Each worker runs a run of consecutive shards as one batch through the network (DpUnet's batched
  // forward and backward give every sample the bits it gets alone); every sample adds its gradient
  // to its shard's, in sample order. So the bytes do not depend on the thread count.
  while (workspaces_.size() < static_cast<std::size_t>(B)) workspaces_.push_back(net_.workspace());
  const unsigned workers = std::max(1u, std::min(resolve_threads(threads), static_cast<unsigned>(n_shards)));
  std::atomic<unsigned> next{0};
  run_workers(workers, [&](unsigned) {
    for (unsigned w = next.fetch_add(1); w < workers; w = next.fetch_add(1)) {
      const int s0 = static_cast<int>(static_cast<std::int64_t>(n_shards) * w / workers);
      const int s1 = static_cast<int>(static_cast<std::int64_t>(n_shards) * (w + 1) / workers);
      const int lo = shard_begin(s0), hi = shard_begin(s1);
      const auto n = static_cast<std::size_t>(hi - lo);
      if (n == 0) continue;
      std::vector<float*> g(n);
      for (int s = s0; s < s1; ++s) {
        std::vector<float>& gs = grads[static_cast<std::size_t>(s)];
        gs.assign(P, 0.0f);
        for (int k = shard_begin(s); k < shard_begin(s + 1); ++k) g[static_cast<std::size_t>(k - lo)] = gs.data();
      }
      std::vector<DpMat<float>> noise(n), noisy(n);
      std::vector<DpVec<float>> cond(n);
      std::vector<double> steps(n);
      for (std::size_t i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(lo) + i;
        Rng rng(derive_seed({seed_, kDpNoiseStream, static_cast<std::uint64_t>(t_), static_cast<std::uint64_t>(k)}));
        const int t = static_cast<int>(rng.uniform_int(static_cast<std::uint64_t>(T)));
        noise[i] = normal_mat(rng, a.action_dim, a.pred_horizon);
        const double ab = schedule_.alphas_cumprod[static_cast<std::size_t>(t)];
        noisy[i] = static_cast<float>(std::sqrt(ab)) * actions[k] + static_cast<float>(std::sqrt(1.0 - ab)) * noise[i];
        steps[i] = t;
        cond[i] = conds[k];
      }
      std::vector<DpUnet<float>::Workspace*> ws(n);
      for (std::size_t i = 0; i < n; ++i) ws[i] = workspaces_[static_cast<std::size_t>(lo) + i].get();
      std::vector<DpMat<float>> diff = net_.forward(params_.data(), noisy, steps, cond, ws);
      for (std::size_t i = 0; i < n; ++i) {
        diff[i] -= noise[i];
        losses[static_cast<std::size_t>(lo) + i] = diff[i].cast<double>().squaredNorm();
        diff[i] *= scale;
      }
      net_.backward(params_.data(), diff, ws, g);
    }
  });
  // fixed-order reductions
  std::vector<float>& g = grads[0];
  for (int s = 1; s < n_shards; ++s) {
    const std::vector<float>& h = grads[static_cast<std::size_t>(s)];
    for (std::size_t i = 0; i < P; ++i) g[i] += h[i];
  }
  double loss = 0.0;
  for (double l : losses) loss += l;
  loss /= static_cast<double>(B) * a.action_dim * a.pred_horizon;

  ++t_;
  const auto lr = static_cast<float>(learning_rate(t_));
  const auto b1 = static_cast<float>(o_.beta1), b2 = static_cast<float>(o_.beta2), eps = static_cast<float>(o_.eps);
  const float c1 = 1.0f - std::pow(b1, static_cast<float>(t_));
  const float c2 = std::sqrt(1.0f - std::pow(b2, static_cast<float>(t_)));
  const float decay = 1.0f - lr * static_cast<float>(o_.weight_decay);
  const auto ema_keep = static_cast<float>(1.0 - ema_decay(t_));
  for (std::size_t i = 0; i < P; ++i) {
    params_[i] *= decay;
    m_[i] = b1 * m_[i] + (1.0f - b1) * g[i];
    v_[i] = b2 * v_[i] + (1.0f - b2) * g[i] * g[i];
    params_[i] -= (lr / c1) * m_[i] / (std::sqrt(v_[i]) / c2 + eps);
    ema_[i] -= ema_keep * (ema_[i] - params_[i]);
  }
  return loss;
}

}  // namespace actionshift::policy
