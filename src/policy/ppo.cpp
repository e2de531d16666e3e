// PPO (clipped objective, GAE, Adam) of a Gaussian actor-critic on Eigen, vectorised rollouts
#include "actionshift/core/error.hpp"
#include "actionshift/policy/ppo.hpp"

#include "actionshift/core/hash.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/workers.hpp"
#include "actionshift/policy/rollout.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/vec_env.hpp"

#include <Eigen/QR>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <stdexcept>

namespace actionshift::policy {
namespace {

constexpr std::uint64_t kPpoStream = 0x7070'6f00'0000'0000ULL;  // keeps PPO seeds apart from evaluation seeds
constexpr int kGradChunks = 8;  // a minibatch gradient is the ordered sum of this many chunk gradients
const float kLogSqrt2Pi = static_cast<float>(0.5 * std::log(2.0 * std::numbers::pi));

using Net = PpoLearner::Net;

// orthogonal matrix (rows x cols) scaled by gain, as torch.nn.init.orthogonal_
Eigen::MatrixXf orthogonal(int rows, int cols, double gain, Rng& rng) {
  const bool transpose = rows < cols;
  const int r = transpose ? cols : rows, c = transpose ? rows : cols;
  Eigen::MatrixXd a(r, c);
  for (int j = 0; j < c; ++j)
    for (int i = 0; i < r; ++i) a(i, j) = rng.normal();
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
  Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(r, c);
  const Eigen::VectorXd d = qr.matrixQR().diagonal();
  for (int j = 0; j < c; ++j)
    if (d(j) < 0) q.col(j) = -q.col(j);
  Eigen::MatrixXd out = transpose ? Eigen::MatrixXd(q.transpose()) : q;
  return (gain * out).cast<float>();
}

Net make_net(const std::vector<int>& sizes, double out_gain, Rng& rng) {
  Net n;
  for (std::size_t i = 0; i + 1 < sizes.size(); ++i) {
    const bool last = i + 2 == sizes.size();
    n.w.push_back(orthogonal(sizes[i + 1], sizes[i], last ? out_gain : std::sqrt(2.0), rng));
    n.b.push_back(Eigen::VectorXf::Zero(sizes[i + 1]));
  }
  return n;
}

Net zeros_like(const Net& n) {
  Net z;
  for (std::size_t i = 0; i < n.w.size(); ++i) {
    z.w.push_back(Eigen::MatrixXf::Zero(n.w[i].rows(), n.w[i].cols()));
    z.b.push_back(Eigen::VectorXf::Zero(n.b[i].size()));
  }
  return z;
}

// act[0] = x, act[i] = tanh(W act[i-1] + b) for hidden layers, act[L] = linear output
void forward(const Net& n, const Eigen::MatrixXf& x, std::vector<Eigen::MatrixXf>& act) {
  const std::size_t layers = n.w.size();
  act.resize(layers + 1);
  act[0] = x;
  for (std::size_t i = 0; i < layers; ++i) {
    Eigen::MatrixXf z = n.w[i] * act[i];
    z.colwise() += n.b[i];
    act[i + 1] = i + 1 < layers ? Eigen::MatrixXf(z.array().tanh()) : z;
  }
}

// accumulate the parameter gradients of a loss whose gradient w.r.t. the output is delta
void backward(const Net& n, const std::vector<Eigen::MatrixXf>& act, Eigen::MatrixXf delta, Net& g) {
  for (std::size_t k = n.w.size(); k-- > 0;) {
    g.w[k].noalias() += delta * act[k].transpose();
    g.b[k] += delta.rowwise().sum();
    if (k > 0) delta = (n.w[k].transpose() * delta).cwiseProduct((1.0f - act[k].array().square()).matrix());
  }
}

void add_into(Net& a, const Net& b) {
  for (std::size_t i = 0; i < a.w.size(); ++i) {
    a.w[i] += b.w[i];
    a.b[i] += b.b[i];
  }
}

double squared_norm(const Net& n) {
  double s = 0.0;
  for (std::size_t i = 0; i < n.w.size(); ++i) s += n.w[i].squaredNorm() + n.b[i].squaredNorm();
  return s;
}

void scale(Net& n, float f) {
  for (std::size_t i = 0; i < n.w.size(); ++i) {
    n.w[i] *= f;
    n.b[i] *= f;
  }
}

template <class T>
void adam(T& p, T& m, T& v, const T& g, float lr, float c1, float c2, float eps) {
  constexpr float b1 = 0.9f, b2 = 0.999f;
  m = b1 * m + (1 - b1) * g;
  v = b2 * v + (1 - b2) * g.cwiseProduct(g);
  p.array() -= (lr / c1) * m.array() / ((v.array() / c2).sqrt() + eps);
}

void adam_net(Net& p, Net& m, Net& v, const Net& g, float lr, float c1, float c2, float eps) {
  for (std::size_t i = 0; i < p.w.size(); ++i) {
    adam(p.w[i], m.w[i], v.w[i], g.w[i], lr, c1, c2, eps);
    adam(p.b[i], m.b[i], v.b[i], g.b[i], lr, c1, c2, eps);
  }
}

// gradient and loss sums of one chunk of a minibatch
struct ChunkGrad {
  Net actor, critic;
  Eigen::VectorXf log_std;
  double policy_loss{0.0}, value_loss{0.0}, approx_kl{0.0};
  std::int64_t clipped{0};
};

std::vector<int> sizes_of(int in, const std::vector<int>& hidden, int out) {
  std::vector<int> s{in};
  s.insert(s.end(), hidden.begin(), hidden.end());
  s.push_back(out);
  return s;
}

}  // namespace

bool bootstraps(bool success, bool truncated, sim::SafetyFlag safety, bool bootstrap_success) {
  if (safety != sim::SafetyFlag::kNone) return false;  // a safety stop is terminal
  return success ? bootstrap_success : truncated;
}

Eigen::VectorXf gae(const Eigen::VectorXf& rewards, const Eigen::VectorXf& values, const Eigen::VectorXf& final_values,
                    const std::vector<std::uint8_t>& ended, const Eigen::VectorXf& next_value, int num_envs, double gamma,
                    double lambda) {
  const Eigen::Index n = rewards.size();
  if (num_envs <= 0 || n % num_envs != 0 || values.size() != n || final_values.size() != n ||
      static_cast<Eigen::Index>(ended.size()) != n || next_value.size() != num_envs)
    throw std::invalid_argument("gae: inconsistent sizes");
  const int steps = static_cast<int>(n / num_envs);
  const float g = static_cast<float>(gamma), gl = static_cast<float>(gamma * lambda);
  Eigen::VectorXf adv(n);
  for (int e = 0; e < num_envs; ++e) {
    float last = 0.0f;
    for (int t = steps - 1; t >= 0; --t) {
      const Eigen::Index k = static_cast<Eigen::Index>(t) * num_envs + e;
      if (ended[static_cast<std::size_t>(k)]) {
        last = rewards(k) + g * final_values(k) - values(k);  // episode over: no carry from the next episode
      } else {
        const float nv = t == steps - 1 ? next_value(e) : values(k + num_envs);
        last = rewards(k) + g * nv - values(k) + gl * last;
      }
      adv(k) = last;
    }
  }
  return adv;
}

PpoLearner::PpoLearner(const PpoOptions& options, int obs_dim) : o_(options) {
  Rng rng(derive_seed({o_.seed, kPpoStream, 0}));
  actor_ = make_net(sizes_of(obs_dim, o_.hidden, kActionDim), 0.01 * std::sqrt(2.0), rng);
  critic_ = make_net(sizes_of(obs_dim, o_.hidden, 1), 1.0, rng);
  log_std_ = Eigen::VectorXf::Constant(kActionDim, static_cast<float>(o_.init_log_std));
  if (o_.init_actor) {
    const MlpWeights& w = *o_.init_actor;
    const std::vector<int> want = sizes_of(w.input_dim(), o_.hidden, kActionDim);
    if (w.task != o_.task || w.layers != want || w.w.size() != actor_.w.size())
      throw std::invalid_argument("PPO warm start: the initial actor's task or hidden widths differ from the run's");
    const int in = w.input_dim();
    if (in != obs_dim && !(w.history == 0 && o_.delay_aware && in == obs_dim - kHistoryLength * kActionDim))
      throw std::invalid_argument("PPO warm start: the initial actor's input (" + std::to_string(in) + ") does not fit the run's (" +
                                  std::to_string(obs_dim) + ")");
    for (std::size_t i = 0; i < actor_.w.size(); ++i) {
      actor_.w[i] = w.w[i];
      actor_.b[i] = w.b[i];
    }
    // fold x_norm = (x - mean) / std into the first layer; zero weights on inputs the actor lacked
    const Eigen::VectorXf inv_std = w.input_std.cwiseInverse();
    Eigen::MatrixXf w0 = Eigen::MatrixXf::Zero(w.w[0].rows(), obs_dim);
    w0.leftCols(in) = w.w[0] * inv_std.asDiagonal();
    actor_.b[0] = w.b[0] - w0.leftCols(in) * w.input_mean;
    actor_.w[0] = w0;
  }
  m_actor_ = zeros_like(actor_);
  v_actor_ = zeros_like(actor_);
  m_critic_ = zeros_like(critic_);
  v_critic_ = zeros_like(critic_);
  m_log_std_ = v_log_std_ = Eigen::VectorXf::Zero(kActionDim);
}

Eigen::MatrixXf PpoLearner::mean(const Eigen::MatrixXf& obs) const {
  std::vector<Eigen::MatrixXf> act;
  forward(actor_, obs, act);
  return act.back();
}

Eigen::VectorXf PpoLearner::value(const Eigen::MatrixXf& obs) const {
  std::vector<Eigen::MatrixXf> act;
  forward(critic_, obs, act);
  return act.back().row(0).transpose();
}

Eigen::VectorXf PpoLearner::log_prob(const Eigen::MatrixXf& mean, const Eigen::MatrixXf& actions) const {
  const Eigen::ArrayXf inv_std = (-log_std_).array().exp();
  const Eigen::ArrayXXf z = (actions - mean).array().colwise() * inv_std;
  const float c = -log_std_.sum() - kActionDim * kLogSqrt2Pi;
  return (-0.5f * z.square().colwise().sum() + c).matrix().transpose();
}

PpoUpdateStats PpoLearner::update(const PpoBatch& batch, std::uint64_t shuffle_seed, unsigned threads) {
  WorkerPool pool(std::min<unsigned>(resolve_threads(threads), kGradChunks));
  return update(batch, shuffle_seed, pool);
}

PpoUpdateStats PpoLearner::update(const PpoBatch& batch, std::uint64_t shuffle_seed, WorkerPool& pool) {
  const Eigen::Index n = batch.size();
  const Eigen::Index mb = n / std::max(1, o_.num_minibatches);
  if (mb < 1) throw std::invalid_argument("PPO update: fewer transitions than minibatches");
  std::vector<Eigen::Index> idx(static_cast<std::size_t>(n));
  std::iota(idx.begin(), idx.end(), Eigen::Index{0});
  Rng rng(shuffle_seed);
  const float clip = static_cast<float>(o_.clip_coef);
  PpoUpdateStats stats;
  const int obs_dim = static_cast<int>(batch.obs.rows());
  Eigen::MatrixXf x(obs_dim, mb), a(kActionDim, mb);
  Eigen::VectorXf old_lp(mb), adv(mb), ret(mb);
  std::vector<ChunkGrad> chunks(kGradChunks);
  for (int epoch = 0; epoch < o_.update_epochs; ++epoch) {
    for (std::size_t i = idx.size(); i > 1; --i) std::swap(idx[i - 1], idx[static_cast<std::size_t>(rng.uniform_int(i))]);
    double pl = 0.0, vl = 0.0, kl = 0.0;
    std::int64_t clipped = 0, seen = 0;
    for (Eigen::Index start = 0; start + mb <= n; start += mb) {
      for (Eigen::Index c = 0; c < mb; ++c) {
        const Eigen::Index k = idx[static_cast<std::size_t>(start + c)];
        x.col(c) = batch.obs.col(k);
        a.col(c) = batch.actions.col(k);
        old_lp(c) = batch.log_probs(k);
        adv(c) = batch.advantages(k);
        ret(c) = batch.returns(k);
      }
      // advantage normalisation over the minibatch (unbiased std, as torch)
      const float am = adv.mean();
      const float as = mb > 1 ? std::sqrt((adv.array() - am).square().sum() / static_cast<float>(mb - 1)) : 0.0f;
      const Eigen::VectorXf nadv = (adv.array() - am) / (as + 1e-8f);
      const float inv_m = 1.0f / static_cast<float>(mb);
      std::atomic<int> next{0};
      pool.run([&](unsigned) {
        while (true) {
          const int ci = next.fetch_add(1);
          if (ci >= kGradChunks) break;
          const Eigen::Index c0 = mb * ci / kGradChunks, c1 = mb * (ci + 1) / kGradChunks, m = c1 - c0;
          ChunkGrad& g = chunks[static_cast<std::size_t>(ci)];
          g = ChunkGrad{zeros_like(actor_), zeros_like(critic_), Eigen::VectorXf::Zero(kActionDim), 0.0, 0.0, 0.0, 0};
          if (m == 0) continue;
          std::vector<Eigen::MatrixXf> act;
          forward(actor_, x.middleCols(c0, m), act);
          const Eigen::MatrixXf diff = a.middleCols(c0, m) - act.back();
          const Eigen::ArrayXf inv_var = (-2.0f * log_std_).array().exp();
          const Eigen::VectorXf lp = log_prob(act.back(), a.middleCols(c0, m));
          Eigen::RowVectorXf g_lp(m);
          for (Eigen::Index j = 0; j < m; ++j) {
            const float logratio = lp(j) - old_lp(c0 + j);
            const float ratio = std::exp(logratio);
            const float A = nadv(c0 + j);
            const float pg1 = -A * ratio, pg2 = -A * std::clamp(ratio, 1.0f - clip, 1.0f + clip);
            g.policy_loss += std::max(pg1, pg2);
            g.approx_kl += (ratio - 1.0f) - logratio;
            if (std::abs(ratio - 1.0f) > clip) ++g.clipped;
            g_lp(j) = pg1 >= pg2 ? -A * ratio * inv_m : 0.0f;  // d loss / d log_prob
          }
          // d log_prob / d mean = diff / var; d log_prob / d log_std = diff^2 / var - 1
          const Eigen::MatrixXf dmean = (diff.array().colwise() * inv_var).rowwise() * g_lp.array();
          g.log_std = (((diff.array().square().colwise() * inv_var) - 1.0f).rowwise() * g_lp.array()).rowwise().sum().matrix();
          g.log_std.array() -= static_cast<float>(o_.ent_coef) * static_cast<float>(m) * inv_m;  // entropy bonus
          backward(actor_, act, dmean, g.actor);
          std::vector<Eigen::MatrixXf> cact;
          forward(critic_, x.middleCols(c0, m), cact);
          const Eigen::RowVectorXf dv = cact.back().row(0) - ret.segment(c0, m).transpose();
          g.value_loss += 0.5 * dv.squaredNorm();
          backward(critic_, cact, Eigen::MatrixXf(static_cast<float>(o_.vf_coef) * inv_m * dv), g.critic);
        }
      });
      ChunkGrad& total = chunks[0];
      for (int ci = 1; ci < kGradChunks; ++ci) {
        const ChunkGrad& g = chunks[static_cast<std::size_t>(ci)];
        add_into(total.actor, g.actor);
        add_into(total.critic, g.critic);
        total.log_std += g.log_std;
        total.policy_loss += g.policy_loss;
        total.value_loss += g.value_loss;
        total.approx_kl += g.approx_kl;
        total.clipped += g.clipped;
      }
      // global gradient-norm clipping over every parameter that learns, then Adam
      const double norm = std::sqrt((actor_frozen_ ? 0.0 : squared_norm(total.actor) + total.log_std.squaredNorm()) +
                                    squared_norm(total.critic));
      if (o_.max_grad_norm > 0 && norm > o_.max_grad_norm) {
        const float f = static_cast<float>(o_.max_grad_norm / (norm + 1e-6));
        scale(total.actor, f);
        scale(total.critic, f);
        total.log_std *= f;
      }
      // Adam step counts per group: a critic warm-up does not advance the frozen actor's bias correction
      const float lr = static_cast<float>(o_.learning_rate), eps = static_cast<float>(o_.adam_eps);
      auto corr = [](int t, float beta) { return 1.0f - std::pow(beta, static_cast<float>(t)); };
      if (!actor_frozen_) {
        ++adam_t_actor_;
        const float a1 = corr(adam_t_actor_, 0.9f), a2 = corr(adam_t_actor_, 0.999f);
        adam_net(actor_, m_actor_, v_actor_, total.actor, lr, a1, a2, eps);
        adam(log_std_, m_log_std_, v_log_std_, total.log_std, lr, a1, a2, eps);
      }
      ++adam_t_;
      const float c1 = corr(adam_t_, 0.9f), c2 = corr(adam_t_, 0.999f);
      adam_net(critic_, m_critic_, v_critic_, total.critic, lr, c1, c2, eps);
      pl += total.policy_loss;
      vl += total.value_loss;
      kl = total.approx_kl * inv_m;  // the last minibatch's, as the baseline's early stop
      clipped += total.clipped;
      seen += mb;
    }
    stats.epochs = epoch + 1;
    stats.policy_loss = pl / static_cast<double>(seen);
    stats.value_loss = vl / static_cast<double>(seen);
    stats.approx_kl = kl;
    stats.clip_fraction = static_cast<double>(clipped) / static_cast<double>(seen);
    if (o_.target_kl > 0 && kl > o_.target_kl) break;
  }
  return stats;
}

MlpWeights PpoLearner::actor_weights(sim::TaskId task, const nlohmann::json& training) const {
  MlpWeights w;
  w.task = task;
  w.history = o_.delay_aware ? kHistoryLength : 0;
  w.layers = sizes_of(static_cast<int>(actor_.w.front().cols()), o_.hidden, kActionDim);
  w.input_mean = Eigen::VectorXf::Zero(w.layers.front());
  w.input_std = Eigen::VectorXf::Ones(w.layers.front());
  w.w = actor_.w;
  w.b = actor_.b;
  w.training = training;
  return w;
}

void check_ppo_options(const PpoOptions& o) {
  if (o.total_steps <= 0) throw InputError("", "total-steps", "must be positive");
  if (o.num_envs <= 0 || o.num_envs > 4096) throw InputError("", "envs", "must be in [1, 4096]");
  if (o.num_steps <= 0) throw InputError("", "rollout-steps", "must be positive");
  if (o.num_minibatches <= 0 || static_cast<std::int64_t>(o.num_envs) * o.num_steps < o.num_minibatches)
    throw InputError("", "minibatches", "must be positive and at most envs x rollout-steps");
  if (o.update_epochs <= 0) throw InputError("", "epochs", "must be positive");
  if (!(o.learning_rate > 0) || !std::isfinite(o.learning_rate)) throw InputError("", "lr", "must be positive");
  if (!(o.gamma >= 0 && o.gamma <= 1)) throw InputError("", "gamma", "must be in [0, 1]");
  if (!(o.gae_lambda >= 0 && o.gae_lambda <= 1)) throw InputError("", "gae-lambda", "must be in [0, 1]");
  if (o.eval_every < 0 || o.eval_episodes < 0) throw InputError("", "eval-every", "--eval-every and --eval-episodes must be non-negative");
  if (o.stop_steps < 0) throw InputError("", "stop-after", "must be non-negative");
  if (!std::isfinite(o.init_log_std) || o.init_log_std < -5 || o.init_log_std > 1)
    throw InputError("", "init-log-std", "must be in [-5, 1]");
  if (o.critic_warmup < 0) throw InputError("", "critic-warmup", "must be non-negative");
  if (o.hidden.empty()) throw InputError("", "hidden", "at least one hidden layer is required");
  for (int h : o.hidden)
    if (h <= 0 || h > 4096) throw InputError("", "hidden", "layer widths must be in [1, 4096]");
}

PpoResult train_ppo(const PpoOptions& o, const nlohmann::json& provenance,
                    const std::function<void(const PpoIteration&)>& progress,
                    const std::function<void(const MlpWeights&)>& checkpoint) {
  check_ppo_options(o);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  const unsigned threads = resolve_threads(o.threads);
  auto model = sim::EnvModel::make(o.task, sim::profile_config(o.profile));
  const int env_obs_dim = model->layout().size();
  const int hist_dim = o.delay_aware ? kHistoryLength * kActionDim : 0;
  const int obs_dim = env_obs_dim + hist_dim;  // network input: observation ++ executed-action history
  const int n_env = o.num_envs, T = o.num_steps;
  const std::int64_t per_iter = static_cast<std::int64_t>(n_env) * T;
  const int iterations = static_cast<int>(std::max<std::int64_t>(1, o.total_steps / per_iter));
  PpoLearner learner(o, obs_dim);

  // the vectorised environment (sim::VecEnv), each environment with its own noise stream and episode
  // counter; a delay-aware run gives each episode the identity contract plus a lag drawn for it. Its pool
  // is the run's one pool: environment steps and gradient chunks
  sim::VecEnv vec(model, std::vector<Contract>(static_cast<std::size_t>(n_env), Contract::identity()),
                  sim::FrameRotation::kLive, threads);
  WorkerPool& pool = vec.pool();
  std::vector<Rng> noise;
  std::vector<std::uint64_t> episode_count(static_cast<std::size_t>(n_env), 0);
  Eigen::MatrixXf cur = Eigen::MatrixXf::Zero(obs_dim, n_env);
  // new episode of env e; writes its first network input (zero history) into cur.col(e)
  auto reset_env = [&](int e) {
    const auto ue = static_cast<std::size_t>(e);
    const std::uint64_t k = episode_count[ue]++;
    const std::uint64_t seed = derive_seed({o.seed, kPpoStream, 2, static_cast<std::uint64_t>(e), k});
    if (o.delay_aware) {
      ContractFields f;
      f.lag = kTrainingLags[derive_seed({o.seed, kPpoStream, 5, static_cast<std::uint64_t>(e), k}) % 4];
      vec.set_contract(e, Contract::make(f));
    }
    cur.col(e).head(env_obs_dim) = vec.env(e).reset(seed).cast<float>();
    if (hist_dim > 0) cur.col(e).tail(hist_dim).setZero();
  };
  for (int e = 0; e < n_env; ++e) {
    noise.emplace_back(derive_seed({o.seed, kPpoStream, 1, static_cast<std::uint64_t>(e)}));
    reset_env(e);
  }

  // per-step storage, column (t * n_env + e)
  PpoBatch batch;
  batch.obs.resize(obs_dim, per_iter);
  batch.actions.resize(kActionDim, per_iter);
  batch.log_probs.resize(per_iter);
  batch.advantages.resize(per_iter);
  batch.returns.resize(per_iter);
  Eigen::VectorXf values(per_iter), rewards(per_iter), final_values = Eigen::VectorXf::Zero(per_iter);
  std::vector<std::uint8_t> ended(static_cast<std::size_t>(per_iter));
  // per-env results of one step, written by the workers by env index
  std::vector<float> step_reward(static_cast<std::size_t>(n_env));
  std::vector<std::uint8_t> step_end(static_cast<std::size_t>(n_env)), step_boot(static_cast<std::size_t>(n_env)),
      step_success(static_cast<std::size_t>(n_env));
  std::vector<double> step_return(static_cast<std::size_t>(n_env));
  Eigen::MatrixXf final_obs(obs_dim, n_env);
  Eigen::MatrixXd act_d(kActionDim, n_env);  // the step's actions as the environments take them, column e for env e

  PpoResult result;
  std::int64_t env_steps = 0;
  for (int it = 0; it < iterations; ++it) {
    PpoIteration rec;
    rec.iteration = it;
    double return_sum = 0.0;
    for (int t = 0; t < T; ++t) {
      const Eigen::MatrixXf mean = learner.mean(cur);
      const Eigen::VectorXf val = learner.value(cur);
      const Eigen::VectorXf std = learner.log_std().array().exp().matrix();
      Eigen::MatrixXf act(kActionDim, n_env);
      for (int e = 0; e < n_env; ++e)
        for (int j = 0; j < kActionDim; ++j)
          act(j, e) = mean(j, e) + std(j) * static_cast<float>(noise[static_cast<std::size_t>(e)].normal());
      const Eigen::VectorXf lp = learner.log_prob(mean, act);
      const Eigen::Index base = static_cast<Eigen::Index>(t) * n_env;
      batch.obs.middleCols(base, n_env) = cur;
      batch.actions.middleCols(base, n_env) = act;
      batch.log_probs.segment(base, n_env) = lp;
      values.segment(base, n_env) = val;
      act_d = act.cast<double>().cwiseMax(-1.0).cwiseMin(1.0);  // same size every step: no allocation
      vec.step(std::span<const double>(act_d.data(), static_cast<std::size_t>(act_d.size())), [&](int e, const sim::StepResult& r) {
        const auto ue = static_cast<std::size_t>(e);
        step_reward[ue] = static_cast<float>(r.reward);
        const bool success = r.success;
        const bool over = r.episode_over();
        step_success[ue] = success ? 1 : 0;
        step_end[ue] = (success || over) ? 1 : 0;
        step_boot[ue] = bootstraps(success, r.truncated, r.safety, o.bootstrap_success) ? 1 : 0;
        // next network input, built in this env's final_obs column (no allocation per step; the
        // column is read only when the episode ended): the observation and, delay-aware, the
        // history shifted by the executed action
        auto next = final_obs.col(e);
        next.head(env_obs_dim) = r.obs.cast<float>();
        if (hist_dim > 0) {
          next.segment(env_obs_dim + kActionDim, hist_dim - kActionDim) = cur.col(e).segment(env_obs_dim, hist_dim - kActionDim);
          next.segment(env_obs_dim, kActionDim) = act_d.col(e).cast<float>();
        }
        if (step_end[ue]) {
          step_return[ue] = vec.env(e).episode().episode_return;
          reset_env(e);  // r is not read after this: the reset (or a new contract) replaces it
        } else {
          cur.col(e) = next;
        }
      });
      bool any_boot = false;
      for (int e = 0; e < n_env; ++e) {
        const auto ue = static_cast<std::size_t>(e);
        rewards(base + e) = step_reward[ue];
        ended[static_cast<std::size_t>(base + e)] = step_end[ue];
        any_boot = any_boot || step_boot[ue];
        if (step_end[ue]) {
          ++rec.episodes;
          rec.successes += step_success[ue];
          return_sum += step_return[ue];
        }
      }
      if (any_boot) {
        const Eigen::VectorXf fv = learner.value(final_obs);
        for (int e = 0; e < n_env; ++e)
          final_values(base + e) = step_boot[static_cast<std::size_t>(e)] ? fv(e) : 0.0f;
      } else {
        final_values.segment(base, n_env).setZero();
      }
    }
    env_steps += per_iter;
    learner.set_actor_frozen(it < o.critic_warmup);
    if (o.anneal_lr)  // ManiSkill ppo.py: lr * (1 - iteration / iterations), set before each update
      learner.set_learning_rate(o.learning_rate * (1.0 - static_cast<double>(it) / static_cast<double>(iterations)));
    batch.advantages = gae(rewards, values, final_values, ended, learner.value(cur), n_env, o.gamma, o.gae_lambda);
    batch.returns = batch.advantages + values;
    const PpoUpdateStats us = learner.update(batch, derive_seed({o.seed, kPpoStream, 4, static_cast<std::uint64_t>(it)}), pool);
    rec.env_steps = env_steps;
    rec.mean_return = rec.episodes > 0 ? return_sum / rec.episodes : std::numeric_limits<double>::quiet_NaN();
    rec.policy_loss = us.policy_loss;
    rec.value_loss = us.value_loss;
    rec.approx_kl = us.approx_kl;
    rec.clip_fraction = us.clip_fraction;
    rec.epochs = us.epochs;
    rec.mean_std = learner.log_std().array().exp().mean();
    const bool stopping = o.stop_steps > 0 && env_steps >= o.stop_steps;
    const bool last_it = it + 1 == iterations || stopping;
    if (o.eval_episodes > 0 && (last_it || (o.eval_every > 0 && (it + 1) % o.eval_every == 0))) {
      nlohmann::json tr = provenance;
      tr["env_steps"] = env_steps;
      tr["iterations"] = it + 1;
      MlpWeights w = learner.actor_weights(o.task, tr);
      auto shared = std::make_shared<const MlpWeights>(w);
      MlpPolicy pol(shared, sha256_hex(serialize_mlp(w)));
      RolloutOptions ro;
      ro.seed = derive_seed({o.seed, kPpoStream, 3});
      ro.episodes = o.eval_episodes;
      ro.threads = threads;
      std::vector<EpisodeOutcome> outcomes;
      if (!o.delay_aware) {
        outcomes = run_episodes(pol, model, ro);
      } else {  // the episodes split over the training lags (contract index = the lag's slot)
        for (int li = 0; li < 4; ++li) {
          ContractFields f;
          f.lag = kTrainingLags[li];
          ro.contract = Contract::make(f);
          ro.contract_index = static_cast<std::uint64_t>(li);
          ro.episodes = o.eval_episodes / 4 + (li < o.eval_episodes % 4 ? 1 : 0);
          if (ro.episodes == 0) continue;
          const auto part = run_episodes(pol, model, ro);
          outcomes.insert(outcomes.end(), part.begin(), part.end());
        }
      }
      int ok = 0;
      double ret = 0.0;
      for (const auto& oc : outcomes) {
        ok += oc.success_once ? 1 : 0;
        ret += oc.episode_return;
      }
      rec.eval_success = static_cast<double>(ok) / static_cast<double>(outcomes.size());
      rec.eval_return = ret / static_cast<double>(outcomes.size());
      w.training["eval_success_once"] = rec.eval_success;
      w.training["eval_episodes"] = o.eval_episodes;
      if (checkpoint) checkpoint(w);
    }
    rec.seconds = elapsed();
    result.iterations.push_back(rec);
    if (progress) progress(rec);
    if (stopping) break;
  }
  nlohmann::json tr = provenance;
  tr["env_steps"] = env_steps;
  tr["iterations"] = static_cast<int>(result.iterations.size());
  result.wall_seconds = elapsed();
  if (!result.iterations.empty() && result.iterations.back().eval_success >= 0) {
    tr["eval_success_once"] = result.iterations.back().eval_success;
    tr["eval_episodes"] = o.eval_episodes;
  }
  result.actor = learner.actor_weights(o.task, tr);
  return result;
}

}  // namespace actionshift::policy
