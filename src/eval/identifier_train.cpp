// Training of the learned identifiers (osi, probe_osi, recurrent_osi): simulator rollouts under the
// identifier_training contracts, softmax heads per contract field, Adam (docs/identifiers.md)
#include "actionshift/eval/identifier_train.hpp"

#include "actionshift/adapt/response.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/workers.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/policy/expert.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"

#include <Eigen/SVD>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace actionshift::eval {
namespace {

using adapt::IdentifierKind;
using adapt::IdentifierWeights;
namespace heads = adapt::heads;

constexpr std::uint64_t kIdentifierStream = 0x6964'656e'7400'0000ULL;  // keeps identifier seeds apart from evaluation seeds
constexpr int kProbeBudget = 6;      // probe_osi: the fixed pulses of the belief methods (registry defaults)
constexpr double kProbeAmplitude = 0.5;
constexpr int kWarmup = 8;           // steps of evidence before the first estimate (registry default)
constexpr double kRandomAmplitude = 0.5;
constexpr float kStdFloor = 1e-4f;

struct Rollout {
  int contract{0};
  std::vector<Eigen::VectorXf> steps;  // raw pose (6) ++ response (6), unnormalised
};

// softmax groups of the heads: (offset, size, label getter)
struct Group {
  int offset, size;
};
std::vector<Group> groups() {
  std::vector<Group> g;
  for (int i = 0; i < kPoseDim; ++i) g.push_back({heads::kPermutation + 6 * i, 6});
  for (int i = 0; i < kPoseDim; ++i) g.push_back({heads::kSign + 2 * i, 2});
  for (int i = 0; i < kPoseDim; ++i) g.push_back({heads::kScale + 7 * i, 7});
  g.push_back({heads::kTarget, 2});
  g.push_back({heads::kFrame, 2});
  g.push_back({heads::kLag, 4});
  g.push_back({heads::kGripper, 2});
  return g;
}
std::vector<int> label_vector(const Contract& c) {
  const auto l = adapt::FieldLabels::of(c);
  std::vector<int> v;
  for (int x : l.permutation) v.push_back(x);
  for (int x : l.sign) v.push_back(x);
  for (int x : l.scale) v.push_back(x);
  v.push_back(l.target);
  v.push_back(l.frame);
  v.push_back(l.lag);
  v.push_back(l.gripper);
  return v;
}

// softmax cross-entropy of every group; writes d loss / d logits (scaled by `scale`) into `grad`; returns the loss
float heads_loss(const Eigen::Ref<const Eigen::MatrixXf>& z, const std::vector<const std::vector<int>*>& labels,
                 const std::vector<float>& mask, float scale, Eigen::MatrixXf& grad) {
  static const std::vector<Group> gs = groups();
  grad.setZero(z.rows(), z.cols());
  float loss = 0.0f;
  for (Eigen::Index b = 0; b < z.cols(); ++b) {
    if (mask[static_cast<std::size_t>(b)] == 0.0f) continue;
    const auto& lab = *labels[static_cast<std::size_t>(b)];
    for (std::size_t k = 0; k < gs.size(); ++k) {
      const auto [o, n] = gs[k];
      const float m = z.col(b).segment(o, n).maxCoeff();
      float sum = 0.0f;
      for (int j = 0; j < n; ++j) sum += std::exp(z(o + j, b) - m);
      const float lse = m + std::log(sum);
      loss += lse - z(o + lab[k], b);
      for (int j = 0; j < n; ++j) grad(o + j, b) = scale * (std::exp(z(o + j, b) - lse) - (j == lab[k] ? 1.0f : 0.0f));
    }
  }
  return loss;
}

// the readout MLP over a batch: activations per layer (tanh hidden, linear last)
std::vector<Eigen::MatrixXf> readout_forward(const IdentifierWeights& w, const Eigen::MatrixXf& x) {
  std::vector<Eigen::MatrixXf> act{x};
  for (std::size_t i = 0; i < w.w.size(); ++i) {
    Eigen::MatrixXf z = w.w[i] * act.back();
    z.colwise() += w.b[i];
    act.push_back(i + 1 < w.w.size() ? Eigen::MatrixXf(z.array().tanh()) : z);
  }
  return act;
}
// back-propagates d loss / d output through the readout, accumulating into g; returns d loss / d input
Eigen::MatrixXf readout_backward(const IdentifierWeights& w, const std::vector<Eigen::MatrixXf>& act, Eigen::MatrixXf delta,
                                 IdentifierWeights& g) {
  for (std::size_t k = w.w.size(); k-- > 0;) {
    g.w[k] += delta * act[k].transpose();
    g.b[k] += delta.rowwise().sum();
    delta = w.w[k].transpose() * delta;
    if (k > 0) delta = delta.cwiseProduct((1.0f - act[k].array().square()).matrix());
  }
  return delta;
}

// every trainable tensor of a network, in a fixed order
std::vector<std::pair<float*, Eigen::Index>> tensors(IdentifierWeights& w) {
  std::vector<std::pair<float*, Eigen::Index>> t;
  if (w.recurrent > 0) {
    t.emplace_back(w.wx.data(), w.wx.size());
    t.emplace_back(w.wh.data(), w.wh.size());
    t.emplace_back(w.bh.data(), w.bh.size());
  }
  for (std::size_t i = 0; i < w.w.size(); ++i) {
    t.emplace_back(w.w[i].data(), w.w[i].size());
    t.emplace_back(w.b[i].data(), w.b[i].size());
  }
  return t;
}
void zero(IdentifierWeights& g) {
  for (auto [p, n] : tensors(g)) std::fill(p, p + n, 0.0f);
}

struct Adam {
  std::vector<std::vector<float>> m, v;
  int t{0};
  void step(IdentifierWeights& w, IdentifierWeights& g, float lr) {
    auto pw = tensors(w);
    auto pg = tensors(g);
    // global-norm clipping at 5 keeps back-propagation through time stable
    double norm = 0.0;
    for (auto [p, n] : pg)
      for (Eigen::Index i = 0; i < n; ++i) norm += static_cast<double>(p[i]) * p[i];
    norm = std::sqrt(norm);
    const float clip = norm > 5.0 ? static_cast<float>(5.0 / norm) : 1.0f;
    if (m.empty())
      for (auto [p, n] : pw) {
        (void)p;
        m.emplace_back(static_cast<std::size_t>(n), 0.0f);
        v.emplace_back(static_cast<std::size_t>(n), 0.0f);
      }
    ++t;
    constexpr float b1 = 0.9f, b2 = 0.999f, eps = 1e-8f;
    const float c1 = 1.0f - std::pow(b1, static_cast<float>(t)), c2 = 1.0f - std::pow(b2, static_cast<float>(t));
    for (std::size_t k = 0; k < pw.size(); ++k) {
      float* p = pw[k].first;
      const float* gr = pg[k].first;
      auto& mk = m[k];
      auto& vk = v[k];
      for (Eigen::Index i = 0; i < pw[k].second; ++i) {
        const float gi = gr[i] * clip;
        const auto u = static_cast<std::size_t>(i);
        mk[u] = b1 * mk[u] + (1 - b1) * gi;
        vk[u] = b2 * vk[u] + (1 - b2) * gi * gi;
        p[i] -= lr * (mk[u] / c1) / (std::sqrt(vk[u] / c2) + eps);
      }
    }
  }
};

void check_options(const TrainIdentifierOptions& o) {
  if (o.episodes_per_contract <= 0 || o.steps <= 0 || o.window <= 0 || o.recurrent <= 0 || o.train_steps < 0 || o.batch <= 0 ||
      !(o.learning_rate > 0) || o.heldout_episodes <= 0 || o.max_contracts < 0)
    throw std::invalid_argument("train identifier: counts, sizes and the learning rate must be positive");
  if (o.excitation != "expert" && o.excitation != "random")
    throw InputError("--excitation", o.excitation, "must be expert or random");
}

// rollouts of `contracts` (episodes_per_contract each), collected in parallel, returned in order
std::vector<Rollout> collect(const TrainIdentifierOptions& o, const std::vector<Contract>& contracts, int episodes,
                             std::uint64_t stream) {
  const sim::TaskId task = sim::parse_task(o.task);
  auto model = sim::EnvModel::make(task, sim::profile_config(o.profile));
  const adapt::TcpSlice slice = tcp_slice(model->layout());
  const int n = static_cast<int>(contracts.size()) * episodes;
  std::vector<Rollout> out(static_cast<std::size_t>(n));
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex mu;
  const bool probes = o.kind == IdentifierKind::kProbeOsi;
  run_workers(resolve_threads(o.threads), [&](unsigned) {
    try {
      while (true) {
        const int k = next.fetch_add(1);
        if (k >= n) break;
        const int ci = k / episodes;
        Rng rng(derive_seed({o.seed, kIdentifierStream, stream, static_cast<std::uint64_t>(k)}));
        sim::HiddenContractEnv env(model, contracts[static_cast<std::size_t>(ci)]);
        Eigen::VectorXd obs = env.reset(rng.next_u64());
        Rollout r;
        r.contract = ci;
        for (int t = 0; t < std::min(o.steps, env.horizon()); ++t) {
          Action raw = Action::Zero();
          if (probes && t < kProbeBudget) {
            raw[t % kPoseDim] = kProbeAmplitude;
          } else if (o.excitation == "random") {
            for (int c = 0; c < kPoseDim; ++c) raw[c] = rng.uniform(-kRandomAmplitude, kRandomAmplitude);
          } else {
            raw = policy::expert_action(task, obs);  // passed through unchanged
          }
          const sim::StepResult& s = env.step(raw);
          const Pose6 resp = adapt::tcp_response(obs, s.obs, slice);
          Eigen::VectorXf f(adapt::kStepFeatures);
          f.head<6>() = raw.head<6>().cast<float>();
          f.tail<6>() = resp.cast<float>();
          r.steps.push_back(f);
          obs = s.obs;
          if (s.episode_over()) break;
        }
        out[static_cast<std::size_t>(k)] = std::move(r);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu);
      if (!error) error = std::current_exception();
    }
  });
  if (error) std::rethrow_exception(error);
  return out;
}

std::vector<Contract> manifest_contracts(bool train, int max_contracts) {
  const Manifest m = data::resolve_manifest("identifier_training");
  std::vector<Contract> c = train ? m.train_contracts() : m.contracts();
  if (max_contracts > 0 && static_cast<int>(c.size()) > max_contracts) c.resize(static_cast<std::size_t>(max_contracts));
  return c;
}

// The paper's dimensional argument, measured: the numerical rank (singular values above 1 % of the
// largest) of the lagged regressor matrix [raw_t, raw_t-1] (12 columns) over the steps the network
// sees at step `t` (a window of `window` steps, or all of them). A one-step-lag linear map of the 6
// pose channels has 12 regressors per output; fewer independent rows cannot determine it.
double regressor_rank(const Rollout& r, int t, int window) {
  const int first = window > 0 ? std::max(1, t - window + 1) : 1;
  const int rows = t - first;
  if (rows <= 0) return 0.0;
  Eigen::MatrixXd x(rows, 12);
  for (int k = 0; k < rows; ++k) {
    const int tau = first + k;  // step index with a predecessor
    x.row(k).head<6>() = r.steps[static_cast<std::size_t>(tau)].head<6>().cast<double>().transpose();
    x.row(k).tail<6>() = r.steps[static_cast<std::size_t>(tau - 1)].head<6>().cast<double>().transpose();
  }
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(x).singularValues();
  if (sv.size() == 0 || sv[0] <= 0.0) return 0.0;
  return static_cast<double>((sv.array() > 0.01 * sv[0]).count());
}

int freeze_point(const IdentifierWeights& w) { return w.kind == IdentifierKind::kProbeOsi ? kProbeBudget + kWarmup : 0; }

IdentifierVerdicts verdicts_on(const IdentifierWeights& w, const std::vector<Rollout>& rollouts, const std::vector<Contract>& contracts,
                               int steps) {
  IdentifierVerdicts v;
  for (int h : {5, 10, 15, 20, 30, 45})
    if (h <= steps) v.horizons.push_back(h);
  v.accuracy.assign(v.horizons.size(), {});
  v.exact.assign(v.horizons.size(), 0.0);
  v.regressor_rank.assign(v.horizons.size(), 0.0);
  v.contracts = static_cast<int>(contracts.size());
  v.episodes = static_cast<int>(rollouts.size());
  auto shared = std::make_shared<const IdentifierWeights>(w);
  const int freeze = freeze_point(w);
  for (const auto& r : rollouts) {
    adapt::IdentifierState st(shared);
    std::optional<Contract> frozen;
    std::size_t hi = 0;
    for (int t = 1; t <= static_cast<int>(r.steps.size()) && hi < v.horizons.size(); ++t) {
      st.feed_normalised((r.steps[static_cast<std::size_t>(t - 1)] - w.feature_mean).cwiseQuotient(w.feature_std));
      if (freeze > 0 && t == freeze) frozen = adapt::decode_logits(st.logits());
      // an episode that ended early keeps its last estimate for the later horizons
      const bool last = t == static_cast<int>(r.steps.size());
      while (hi < v.horizons.size() && (v.horizons[hi] == t || (last && v.horizons[hi] > t))) {
        const Contract est = frozen && v.horizons[hi] >= freeze ? *frozen : adapt::decode_logits(st.logits());
        const Contract& truth = contracts[static_cast<std::size_t>(r.contract)];
        const auto a = adapt::field_agreement(est, truth);
        for (std::size_t f = 0; f < 7; ++f) v.accuracy[hi][f] += a[f];
        v.exact[hi] += est == truth ? 1.0 : 0.0;
        v.regressor_rank[hi] += regressor_rank(r, std::min(t, frozen ? freeze : t), w.window);
        ++hi;
      }
    }
  }
  for (std::size_t h = 0; h < v.horizons.size(); ++h) {
    for (double& a : v.accuracy[h]) a /= std::max<double>(1, static_cast<double>(rollouts.size()));
    v.exact[h] /= std::max<double>(1, static_cast<double>(rollouts.size()));
    v.regressor_rank[h] /= std::max<double>(1, static_cast<double>(rollouts.size()));
  }
  return v;
}

std::vector<int> hidden_of(IdentifierKind kind) { return kind == IdentifierKind::kRecurrentOsi ? std::vector<int>{64} : std::vector<int>{64, 64}; }

}  // namespace

nlohmann::json IdentifierVerdicts::to_json() const {
  nlohmann::json acc = nlohmann::json::object();
  for (std::size_t f = 0; f < 7; ++f) {
    nlohmann::json row = nlohmann::json::array();
    for (const auto& a : accuracy) row.push_back(std::round(a[f] * 1e4) / 1e4);
    acc[adapt::kFieldNames[f]] = row;
  }
  nlohmann::json ex = nlohmann::json::array();
  for (double e : exact) ex.push_back(std::round(e * 1e4) / 1e4);
  nlohmann::json rank = nlohmann::json::array();
  for (double e : regressor_rank) rank.push_back(std::round(e * 100) / 100);
  return {{"horizons", horizons}, {"field_accuracy", acc}, {"exact_contract", ex}, {"regressor_rank", rank},
          {"contracts", contracts}, {"episodes", episodes}};
}

std::int64_t identifier_parameter_count(IdentifierKind kind, const TrainIdentifierOptions& o) {
  const bool rec = kind == IdentifierKind::kRecurrentOsi;
  return IdentifierWeights::init(kind, o.task, rec ? 0 : o.window, rec ? o.recurrent : 0, hidden_of(kind), 1).parameter_count();
}

IdentifierVerdicts evaluate_identifier(const IdentifierWeights& w, const TrainIdentifierOptions& opt) {
  TrainIdentifierOptions o = opt;
  o.kind = w.kind;
  check_options(o);
  const auto contracts = manifest_contracts(false, o.max_contracts);
  return verdicts_on(w, collect(o, contracts, o.heldout_episodes, 0x4e1d), contracts, o.steps);
}

TrainIdentifierResult train_identifier(const TrainIdentifierOptions& o, const std::function<void(const std::string&)>& progress) {
  check_options(o);
  (void)sim::parse_task(o.task);
  (void)sim::profile_config(o.profile);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  const bool rec = o.kind == IdentifierKind::kRecurrentOsi;
  IdentifierWeights net = IdentifierWeights::init(o.kind, o.task, rec ? 0 : o.window, rec ? o.recurrent : 0, hidden_of(o.kind),
                                                  derive_seed({o.seed, kIdentifierStream, 0xffff}));
  const auto train_contracts = manifest_contracts(true, o.max_contracts);
  const auto heldout_contracts = manifest_contracts(false, o.max_contracts);
  const std::vector<Rollout> data = collect(o, train_contracts, o.episodes_per_contract, 0x7a1);
  std::int64_t n_steps = 0;
  for (const auto& r : data) n_steps += static_cast<std::int64_t>(r.steps.size());
  say("collected " + std::to_string(data.size()) + " rollouts (" + std::to_string(n_steps) + " steps) under " +
      std::to_string(train_contracts.size()) + " training contracts in " + std::to_string(static_cast<int>(elapsed())) + " s");
  if (n_steps == 0) throw std::invalid_argument("train identifier: no data");

  // normalisation from the training data
  {
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(adapt::kStepFeatures), sq = sum;
    for (const auto& r : data)
      for (const auto& f : r.steps) {
        const Eigen::VectorXd d = f.cast<double>();
        sum += d;
        sq += d.cwiseProduct(d);
      }
    const Eigen::VectorXd mean = sum / static_cast<double>(n_steps);
    const Eigen::VectorXd var = (sq / static_cast<double>(n_steps) - mean.cwiseProduct(mean)).cwiseMax(0.0);
    net.feature_mean = mean.cast<float>();
    net.feature_std = var.cwiseSqrt().cast<float>().cwiseMax(kStdFloor);
  }
  std::vector<std::vector<Eigen::VectorXf>> norm(data.size());
  for (std::size_t e = 0; e < data.size(); ++e)
    for (const auto& f : data[e].steps) norm[e].push_back((f - net.feature_mean).cwiseQuotient(net.feature_std));
  std::vector<std::vector<int>> labels;
  for (const auto& c : train_contracts) labels.push_back(label_vector(c));

  IdentifierWeights grad = net;
  Adam adam;
  Rng batch_rng(derive_seed({o.seed, kIdentifierStream, 0xbbbb}));
  const int feat = adapt::kStepFeatures;
  const int freeze = freeze_point(net);
  double loss_sum = 0.0;
  int loss_n = 0;
  double final_loss = 0.0;
  for (int s = 0; s < o.train_steps; ++s) {
    zero(grad);
    const float lr = static_cast<float>(s >= o.train_steps * 3 / 4 ? 0.3 * o.learning_rate : o.learning_rate);
    float loss = 0.0f;
    if (!rec) {
      // a batch of windows: (rollout, end step) uniformly; zeros before the episode's start
      const int B = o.batch;
      Eigen::MatrixXf x = Eigen::MatrixXf::Zero(o.window * feat, B);
      std::vector<const std::vector<int>*> lab(static_cast<std::size_t>(B));
      for (int b = 0; b < B; ++b) {
        std::size_t e;
        do e = static_cast<std::size_t>(batch_rng.uniform_int(data.size()));
        while (norm[e].empty());
        int len = static_cast<int>(norm[e].size());
        if (freeze > 0) len = std::min(len, freeze);
        const int end = 1 + static_cast<int>(batch_rng.uniform_int(static_cast<std::uint64_t>(len)));  // steps seen
        for (int k = 0; k < o.window; ++k) {
          const int t = end - o.window + k;
          if (t >= 0) x.col(b).segment(k * feat, feat) = norm[e][static_cast<std::size_t>(t)];
        }
        lab[static_cast<std::size_t>(b)] = &labels[static_cast<std::size_t>(data[e].contract)];
      }
      const auto act = readout_forward(net, x);
      Eigen::MatrixXf dz;
      loss = heads_loss(act.back(), lab, std::vector<float>(static_cast<std::size_t>(B), 1.0f), 1.0f / static_cast<float>(B), dz) /
             static_cast<float>(B);
      readout_backward(net, act, dz, grad);
    } else {
      // a batch of whole rollouts, supervised at every step, back-propagated through time
      const int B = std::max(1, o.batch / 8);
      std::vector<std::size_t> eps(static_cast<std::size_t>(B));
      int T = 0;
      for (auto& e : eps) {
        e = static_cast<std::size_t>(batch_rng.uniform_int(data.size()));
        T = std::max(T, static_cast<int>(norm[e].size()));
      }
      std::vector<const std::vector<int>*> lab;
      for (auto e : eps) lab.push_back(&labels[static_cast<std::size_t>(data[e].contract)]);
      std::vector<Eigen::MatrixXf> xs(static_cast<std::size_t>(T)), hs(static_cast<std::size_t>(T) + 1);
      std::vector<std::vector<float>> masks(static_cast<std::size_t>(T));
      hs[0] = Eigen::MatrixXf::Zero(net.recurrent, B);
      float valid = 0.0f;
      for (int t = 0; t < T; ++t) {
        auto& x = xs[static_cast<std::size_t>(t)];
        x = Eigen::MatrixXf::Zero(feat, B);
        masks[static_cast<std::size_t>(t)].assign(static_cast<std::size_t>(B), 0.0f);
        for (int b = 0; b < B; ++b)
          if (t < static_cast<int>(norm[eps[static_cast<std::size_t>(b)]].size())) {
            x.col(b) = norm[eps[static_cast<std::size_t>(b)]][static_cast<std::size_t>(t)];
            masks[static_cast<std::size_t>(t)][static_cast<std::size_t>(b)] = 1.0f;
            valid += 1.0f;
          }
        Eigen::MatrixXf pre = net.wx * x + net.wh * hs[static_cast<std::size_t>(t)];
        pre.colwise() += net.bh;
        hs[static_cast<std::size_t>(t) + 1] = pre.array().tanh().matrix();
      }
      std::vector<Eigen::MatrixXf> dh_out(static_cast<std::size_t>(T));
      for (int t = 0; t < T; ++t) {
        const auto act = readout_forward(net, hs[static_cast<std::size_t>(t) + 1]);
        Eigen::MatrixXf dz;
        loss += heads_loss(act.back(), lab, masks[static_cast<std::size_t>(t)], 1.0f / valid, dz);
        dh_out[static_cast<std::size_t>(t)] = readout_backward(net, act, dz, grad);
      }
      loss /= valid;
      Eigen::MatrixXf dh_next = Eigen::MatrixXf::Zero(net.recurrent, B);
      for (int t = T; t-- > 0;) {
        const Eigen::MatrixXf& h = hs[static_cast<std::size_t>(t) + 1];
        Eigen::MatrixXf dpre = (dh_out[static_cast<std::size_t>(t)] + dh_next).cwiseProduct((1.0f - h.array().square()).matrix());
        for (int b = 0; b < B; ++b)
          if (masks[static_cast<std::size_t>(t)][static_cast<std::size_t>(b)] == 0.0f) dpre.col(b).setZero();
        grad.wx += dpre * xs[static_cast<std::size_t>(t)].transpose();
        grad.wh += dpre * hs[static_cast<std::size_t>(t)].transpose();
        grad.bh += dpre.rowwise().sum();
        dh_next = net.wh.transpose() * dpre;
      }
    }
    adam.step(net, grad, lr);
    loss_sum += loss;
    ++loss_n;
    if ((s + 1) % 500 == 0 || s + 1 == o.train_steps) {
      final_loss = loss_sum / loss_n;
      say("step " + std::to_string(s + 1) + "/" + std::to_string(o.train_steps) + ": loss " + std::to_string(final_loss) + ", " +
          std::to_string(static_cast<int>(elapsed())) + " s");
      loss_sum = 0.0;
      loss_n = 0;
    }
  }
  TrainIdentifierResult result;
  result.final_loss = final_loss;
  const auto heldout = collect(o, heldout_contracts, o.heldout_episodes, 0x4e1d);
  result.heldout = verdicts_on(net, heldout, heldout_contracts, o.steps);
  result.wall_seconds = elapsed();
  result.weights = std::move(net);
  return result;
}

}  // namespace actionshift::eval
