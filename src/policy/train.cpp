// DAgger behaviour cloning of the MLP backbone from the scripted experts (Eigen, Adam)
#include "actionshift/core/error.hpp"
#include "actionshift/policy/train.hpp"

#include "actionshift/core/workers.hpp"

#include "actionshift/core/contract.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/policy/delay_aware.hpp"
#include "actionshift/policy/expert.hpp"
#include "actionshift/policy/rollout.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

namespace actionshift::policy {
namespace {

constexpr std::uint64_t kTrainStream = 0x7472'6169'6e00'0000ULL;  // keeps training seeds apart from evaluation seeds
constexpr float kStdFloor = 1e-2f;

// one collected episode: raw inputs (obs ++ history) and expert labels
struct EpisodeData {
  std::vector<Eigen::VectorXf> inputs;
  std::vector<Action> labels;
  bool success{false};
};

// collect one episode with the learner/expert mixture
template <class EnvT>
EpisodeData collect(EnvT& env, sim::TaskId task, const MlpWeights* learner, double beta, int lag, std::uint64_t env_seed,
                    Rng& rng, int history) {
  EpisodeData d;
  std::optional<DelayAwareExpert> teacher;
  if (history > 0) teacher.emplace(task, lag);
  Eigen::VectorXd obs = env.reset(env_seed);
  const int obs_dim = static_cast<int>(obs.size());
  Eigen::VectorXf input = Eigen::VectorXf::Zero(obs_dim + kActionDim * history);
  while (true) {
    input.head(obs_dim) = obs.cast<float>();
    const Action label = teacher ? teacher->act(obs) : expert_action(task, obs);
    d.inputs.push_back(input);
    d.labels.push_back(label);
    Action executed = label;
    if (learner != nullptr && rng.uniform() >= beta) executed = mlp_forward(*learner, input);
    if (teacher) teacher->override_last_action(executed);
    if (history > 0) {
      const int h = history * kActionDim;
      Eigen::VectorXf hist = input.segment(obs_dim, h);
      input.segment(obs_dim + kActionDim, h - kActionDim) = hist.head(h - kActionDim);
      input.segment(obs_dim, kActionDim) = executed.cast<float>();
    }
    const sim::StepResult& r = env.step(executed);
    obs = r.obs;
    if (r.episode_over()) break;
  }
  d.success = env.episode().success_once;
  return d;
}

// Adam state for every tensor of a network
struct Adam {
  std::vector<Eigen::MatrixXf> mw, vw;
  std::vector<Eigen::VectorXf> mb, vb;
  int t{0};
  explicit Adam(const MlpWeights& m) {
    for (std::size_t i = 0; i < m.w.size(); ++i) {
      mw.push_back(Eigen::MatrixXf::Zero(m.w[i].rows(), m.w[i].cols()));
      vw.push_back(mw.back());
      mb.push_back(Eigen::VectorXf::Zero(m.b[i].size()));
      vb.push_back(mb.back());
    }
  }
};

template <class T>
void adam_update(T& p, T& m, T& v, const T& g, float lr, float c1, float c2) {
  constexpr float b1 = 0.9f, b2 = 0.999f, eps = 1e-8f;
  m = b1 * m + (1 - b1) * g;
  v = b2 * v + (1 - b2) * g.cwiseProduct(g);
  p.array() -= lr * (m.array() / c1) / ((v.array() / c2).sqrt() + eps);
}

// one Adam step on a minibatch of normalised inputs X (in x B) and targets Y (7 x B); returns the loss
float train_step(MlpWeights& m, Adam& adam, const Eigen::MatrixXf& x, const Eigen::MatrixXf& y,
                 const Eigen::VectorXf& out_weight, float lr) {
  const std::size_t n_layers = m.w.size();
  const float batch = static_cast<float>(x.cols());
  std::vector<Eigen::MatrixXf> act(n_layers + 1);
  act[0] = x;
  for (std::size_t i = 0; i < n_layers; ++i) {
    Eigen::MatrixXf z = m.w[i] * act[i];
    z.colwise() += m.b[i];
    act[i + 1] = i + 1 < n_layers ? Eigen::MatrixXf(z.array().tanh()) : z;
  }
  // weighted mean squared error over outputs and batch
  const Eigen::MatrixXf diff = act[n_layers] - y;
  const float loss = (out_weight.asDiagonal() * diff.cwiseProduct(diff)).sum() / (batch * kActionDim);
  Eigen::MatrixXf delta = (2.0f / (batch * kActionDim)) * (out_weight.asDiagonal() * diff);
  ++adam.t;
  const float c1 = 1.0f - std::pow(0.9f, static_cast<float>(adam.t));
  const float c2 = 1.0f - std::pow(0.999f, static_cast<float>(adam.t));
  for (std::size_t k = n_layers; k-- > 0;) {
    const Eigen::MatrixXf gw = delta * act[k].transpose();
    const Eigen::VectorXf gb = delta.rowwise().sum();
    if (k > 0) delta = (m.w[k].transpose() * delta).cwiseProduct((1.0f - act[k].array().square()).matrix());
    adam_update(m.w[k], adam.mw[k], adam.vw[k], gw, lr, c1, c2);
    adam_update(m.b[k], adam.mb[k], adam.vb[k], gb, lr, c1, c2);
  }
  return loss;
}

}  // namespace

void check_train_bc_options(const TrainBcOptions& o) {
  if (o.iterations <= 0 || o.episodes_per_iteration <= 0 || o.steps_per_iteration < 0)
    throw InputError("", "train bc", "--iterations and --episodes must be positive, --steps non-negative");
  if (o.batch_size <= 0 || o.hidden.empty() || !(o.learning_rate > 0))
    throw InputError("", "train bc", "batch size, hidden layers and learning rate must be positive");
}

TrainBcResult train_bc(const TrainBcOptions& o, const std::function<void(const TrainIteration&)>& progress) {
  check_train_bc_options(o);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  const int history = o.delay_aware ? kHistoryLength : 0;
  auto model = sim::EnvModel::make(o.task, sim::profile_config(o.profile));
  MlpWeights net = MlpWeights::init(o.task, history, o.hidden, derive_seed({o.seed, kTrainStream, 0xffff}));
  const int in_dim = net.input_dim();
  Eigen::VectorXf out_weight = Eigen::VectorXf::Ones(kActionDim);
  out_weight(kGripper) = static_cast<float>(o.gripper_weight);

  std::vector<Eigen::VectorXf> data_x;  // normalised inputs
  std::vector<Action> data_y;
  Adam adam(net);
  Rng batch_rng(derive_seed({o.seed, kTrainStream, 0xbbbb}));
  TrainBcResult result;
  const unsigned threads = resolve_threads(o.threads);

  for (int it = 0; it < o.iterations; ++it) {
    const double beta = it == 0 ? 1.0 : std::pow(0.5, it);
    const MlpWeights* learner = it == 0 ? nullptr : &net;
    // collect episodes in parallel, one env per thread; aggregate in episode order
    std::vector<EpisodeData> episodes(static_cast<std::size_t>(o.episodes_per_iteration));
    std::atomic<int> next{0};
    std::exception_ptr error;
    std::mutex mu;
    auto worker = [&] {
      try {
        std::optional<sim::Env> env;
        if (!o.delay_aware) env.emplace(model);
        while (true) {
          const int k = next.fetch_add(1);
          if (k >= o.episodes_per_iteration) break;
          Rng rng(derive_seed({o.seed, kTrainStream, static_cast<std::uint64_t>(it), static_cast<std::uint64_t>(k)}));
          const std::uint64_t env_seed = rng.next_u64();
          const int lag = o.delay_aware ? kTrainingLags[rng.uniform_int(4)] : 0;
          if (o.delay_aware) {
            ContractFields f;
            f.lag = lag;
            sim::HiddenContractEnv henv(model, Contract::make(f));
            episodes[static_cast<std::size_t>(k)] = collect(henv, o.task, learner, beta, lag, env_seed, rng, history);
          } else {
            episodes[static_cast<std::size_t>(k)] = collect(*env, o.task, learner, beta, lag, env_seed, rng, history);
          }
        }
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        if (!error) error = std::current_exception();
      }
    };
    run_workers(threads, [&](unsigned) { worker(); });
    if (error) std::rethrow_exception(error);

    // normalisation from the expert's data (iteration 0), fixed afterwards
    if (it == 0) {
      Eigen::VectorXd sum = Eigen::VectorXd::Zero(in_dim), sq = Eigen::VectorXd::Zero(in_dim);
      std::int64_t n = 0;
      for (const auto& e : episodes)
        for (const auto& x : e.inputs) {
          const Eigen::VectorXd xd = x.cast<double>();
          sum += xd;
          sq += xd.cwiseProduct(xd);
          ++n;
        }
      const Eigen::VectorXd mean = sum / static_cast<double>(n);
      const Eigen::VectorXd var = (sq / static_cast<double>(n) - mean.cwiseProduct(mean)).cwiseMax(0.0);
      net.input_mean = mean.cast<float>();
      net.input_std = var.cwiseSqrt().cast<float>().cwiseMax(kStdFloor);
    }
    int successes = 0;
    for (const auto& e : episodes) {
      successes += e.success ? 1 : 0;
      for (std::size_t j = 0; j < e.inputs.size(); ++j) {
        data_x.push_back((e.inputs[j] - net.input_mean).cwiseQuotient(net.input_std));
        data_y.push_back(e.labels[j]);
      }
    }

    // Adam on minibatches drawn with replacement from the aggregated set
    const float lr = static_cast<float>(it + 1 == o.iterations ? 0.3 * o.learning_rate : o.learning_rate);
    Eigen::MatrixXf xb(in_dim, o.batch_size), yb(kActionDim, o.batch_size);
    double loss_sum = 0.0;
    int loss_n = 0;
    for (int s = 0; s < o.steps_per_iteration; ++s) {
      for (int c = 0; c < o.batch_size; ++c) {
        const auto idx = static_cast<std::size_t>(batch_rng.uniform_int(data_x.size()));
        xb.col(c) = data_x[idx];
        yb.col(c) = data_y[idx].cast<float>();
      }
      const float loss = train_step(net, adam, xb, yb, out_weight, lr);
      if (s >= o.steps_per_iteration - 100) {
        loss_sum += loss;
        ++loss_n;
      }
    }
    TrainIteration rec;
    rec.iteration = it;
    rec.beta = beta;
    rec.samples = static_cast<std::int64_t>(data_x.size());
    rec.episodes = o.episodes_per_iteration;
    rec.successes = successes;
    rec.loss = loss_n > 0 ? loss_sum / loss_n : 0.0;
    rec.seconds = elapsed();
    result.iterations.push_back(rec);
    if (progress) progress(rec);
  }
  result.wall_seconds = elapsed();
  result.weights = std::move(net);
  return result;
}

}  // namespace actionshift::policy
