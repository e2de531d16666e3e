// MLP backbone: weight file format, forward pass, policy
#include "actionshift/policy/mlp.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/weight_file.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace actionshift::policy {
namespace {

constexpr char kMagic[8] = {'A', 'S', 'M', 'L', 'P', 'W', '\0', '\1'};
constexpr std::uint32_t kFormatVersion = 1;
constexpr int kMaxLayerWidth = 4096;
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 30;  // 1 GiB; the shipped networks are < 1 MiB


std::string payload_bytes(const MlpWeights& w) {
  std::string out;
  auto put = [&out](const float* p, Eigen::Index n) { out.append(reinterpret_cast<const char*>(p), static_cast<std::size_t>(n) * 4); };
  put(w.input_mean.data(), w.input_mean.size());
  put(w.input_std.data(), w.input_std.size());
  for (std::size_t i = 0; i < w.w.size(); ++i) {
    // row-major W
    const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = w.w[i];
    put(rm.data(), rm.size());
    put(w.b[i].data(), w.b[i].size());
  }
  return out;
}

std::int64_t payload_floats(const std::vector<int>& layers) {
  return 2 * static_cast<std::int64_t>(layers.front()) + mlp_parameter_count(layers);
}

}  // namespace

std::int64_t mlp_parameter_count(const std::vector<int>& layers) {
  std::int64_t n = 0;
  for (std::size_t i = 0; i + 1 < layers.size(); ++i)
    n += static_cast<std::int64_t>(layers[i]) * layers[i + 1] + layers[i + 1];
  return n;
}

std::int64_t MlpWeights::parameter_count() const { return mlp_parameter_count(layers); }

MlpWeights MlpWeights::init(sim::TaskId task, int history, const std::vector<int>& hidden, std::uint64_t seed) {
  MlpWeights m;
  m.task = task;
  m.history = history;
  m.layers.push_back(sim::observation_layout(task).size() + kActionDim * history);
  for (int h : hidden) m.layers.push_back(h);
  m.layers.push_back(kActionDim);
  m.input_mean = Eigen::VectorXf::Zero(m.layers.front());
  m.input_std = Eigen::VectorXf::Ones(m.layers.front());
  Rng rng(seed);
  for (std::size_t i = 0; i + 1 < m.layers.size(); ++i) {
    const int in = m.layers[i], out = m.layers[i + 1];
    const double limit = std::sqrt(6.0 / (in + out));
    Eigen::MatrixXf w(out, in);
    for (int r = 0; r < out; ++r)
      for (int c = 0; c < in; ++c) w(r, c) = static_cast<float>(rng.uniform(-limit, limit));
    m.w.push_back(w);
    m.b.push_back(Eigen::VectorXf::Zero(out));
  }
  return m;
}

std::string serialize_mlp(const MlpWeights& w) {
  const std::string payload = payload_bytes(w);
  nlohmann::json h = {{"format", "actionshift-mlp"},
                      {"version", kFormatVersion},
                      {"task", std::string(sim::task_name(w.task))},
                      {"obs_dim", sim::observation_layout(w.task).size()},
                      {"history", w.history},
                      {"input_dim", w.input_dim()},
                      {"layers", w.layers},
                      {"activation", "tanh"},
                      {"output", "clip[-1,1]"},
                      {"parameters", w.parameter_count()},
                      {"payload_floats", payload.size() / 4},
                      {"payload_sha256", sha256_hex(payload)},
                      {"training", w.training}};
  return weight_file::frame(std::string_view(kMagic, 8), kFormatVersion, h, payload);
}

MlpWeights parse_mlp(std::string_view bytes, const std::string& source) {
  auto fail = [&source](const std::string& field, const std::string& reason) -> InputError {
    return InputError(source, field, reason);
  };
  const weight_file::Unframed u = weight_file::unframe(bytes, std::string_view(kMagic, 8), kFormatVersion, source, "MLP weight file");
  const nlohmann::json& h = u.header;
  auto need = [&](const char* key) -> const nlohmann::json& {
    if (!h.contains(key)) throw fail(std::string("header.") + key, "missing");
    return h.at(key);
  };
  // a JSON integer that fits an int; nlohmann's get<int>() would convert 1e30 with undefined behaviour
  auto small_int = [&](const nlohmann::json& v, const std::string& field) -> int {
    if (v.is_number_unsigned() && v.get<std::uint64_t>() <= static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
      return static_cast<int>(v.get<std::uint64_t>());
    if (v.is_number_integer() && !v.is_number_unsigned() && v.get<std::int64_t>() >= std::numeric_limits<int>::min() &&
        v.get<std::int64_t>() <= std::numeric_limits<int>::max())
      return static_cast<int>(v.get<std::int64_t>());
    throw fail(field, "expected an integer in the range of int (got " + v.dump() + ")");
  };
  MlpWeights w;
  try {
    if (need("format") != "actionshift-mlp") throw fail("header.format", "expected \"actionshift-mlp\"");
    w.task = sim::parse_task(need("task").get<std::string>());
    w.history = small_int(need("history"), "header.history");
    if (w.history != 0 && w.history != kHistoryLength)
      throw fail("header.history", "must be 0 or " + std::to_string(kHistoryLength) + " (got " + std::to_string(w.history) + ")");
    const nlohmann::json& layers = need("layers");
    if (!layers.is_array()) throw fail("header.layers", "expected a list of integers");
    for (const auto& n : layers) w.layers.push_back(small_int(n, "header.layers"));
    if (h.contains("training")) w.training = h.at("training");
  } catch (const nlohmann::json::exception& e) {
    throw fail("header", std::string("wrong field type: ") + e.what());
  } catch (const InputError& e) {
    if (e.source() == source) throw;
    throw fail("header.task", e.reason());
  }
  // shapes must match the task's observation
  const int obs_dim = sim::observation_layout(w.task).size();
  const int expected_in = obs_dim + kActionDim * w.history;
  if (w.layers.size() < 2) throw fail("header.layers", "needs at least an input and an output size");
  for (int n : w.layers)
    if (n <= 0 || n > kMaxLayerWidth) throw fail("header.layers", "layer size " + std::to_string(n) + " out of range [1, 4096]");
  if (w.layers.front() != expected_in)
    throw fail("header.layers", "input size " + std::to_string(w.layers.front()) + " does not match task " +
                                    std::string(sim::task_name(w.task)) + " (expected " + std::to_string(expected_in) + ")");
  if (w.layers.back() != kActionDim)
    throw fail("header.layers", "output size " + std::to_string(w.layers.back()) + " (expected 7)");
  const std::int64_t floats = payload_floats(w.layers);
  // the descriptive fields must describe this file: a reader of the header alone is told the truth
  auto expect = [&](const char* key, const nlohmann::json& want) {
    const nlohmann::json& got = need(key);
    if (got != want) throw fail(std::string("header.") + key, "expected " + want.dump() + " (got " + got.dump() + ")");
  };
  expect("version", kFormatVersion);
  expect("activation", "tanh");
  expect("output", "clip[-1,1]");
  expect("obs_dim", obs_dim);
  expect("input_dim", expected_in);
  expect("payload_floats", floats);
  expect("parameters", mlp_parameter_count(w.layers));
  weight_file::check_payload(u, floats, source, false, " for layers of the header");
  const std::string_view payload = u.payload;
  // read the arrays
  std::size_t at = 0;
  auto take = [&](float* dst, std::int64_t n) {
    std::memcpy(dst, payload.data() + at, static_cast<std::size_t>(n) * 4);
    at += static_cast<std::size_t>(n) * 4;
  };
  const int in = w.layers.front();
  w.input_mean.resize(in);
  w.input_std.resize(in);
  take(w.input_mean.data(), in);
  take(w.input_std.data(), in);
  for (std::size_t i = 0; i + 1 < w.layers.size(); ++i) {
    Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm(w.layers[i + 1], w.layers[i]);
    take(rm.data(), rm.size());
    w.w.emplace_back(rm);
    Eigen::VectorXf b(w.layers[i + 1]);
    take(b.data(), b.size());
    w.b.push_back(b);
  }
  auto finite = [](const auto& m) { return m.allFinite(); };
  bool ok = finite(w.input_mean) && finite(w.input_std) && (w.input_std.array() > 0.0f).all();
  for (std::size_t i = 0; i < w.w.size(); ++i) ok = ok && finite(w.w[i]) && finite(w.b[i]);
  if (!ok) throw fail("payload", "non-finite weight or non-positive input_std");
  return w;
}

void save_mlp(const MlpWeights& w, const std::string& path) { write_file_atomic(path, serialize_mlp(w)); }

MlpWeights load_mlp(const std::string& path) { return parse_mlp(weight_file::read(path, kMaxFileBytes, "weight file"), path); }

Action mlp_forward(const MlpWeights& w, const Eigen::Ref<const Eigen::VectorXf>& x) {
  Eigen::VectorXf h = (x - w.input_mean).cwiseQuotient(w.input_std);
  for (std::size_t i = 0; i < w.w.size(); ++i) {
    Eigen::VectorXf z = w.w[i] * h + w.b[i];
    h = i + 1 < w.w.size() ? Eigen::VectorXf(z.array().tanh()) : z;
  }
  return h.cast<double>().cwiseMax(-1.0).cwiseMin(1.0);
}

MlpPolicy::MlpPolicy(std::shared_ptr<const MlpWeights> weights, std::string sha256, std::string name)
    : weights_(std::move(weights)), sha256_(std::move(sha256)), name_(std::move(name)) {
  input_ = Eigen::VectorXf::Zero(weights_->input_dim());
}

std::unique_ptr<MlpPolicy> MlpPolicy::from_file(const std::string& path, const std::string& name) {
  const std::string bytes = weight_file::read(path, kMaxFileBytes, "weight file");
  auto w = std::make_shared<const MlpWeights>(parse_mlp(bytes, path));
  return std::make_unique<MlpPolicy>(std::move(w), sha256_hex(bytes), name);
}

void MlpPolicy::reset() { input_.setZero(); }

Action MlpPolicy::act(const Eigen::Ref<const Eigen::VectorXd>& obs) {
  check_observation(obs, weights_->task);
  const int d = static_cast<int>(obs.size());
  input_.head(d) = obs.cast<float>();
  const Action a = mlp_forward(*weights_, input_);
  if (weights_->history > 0) {
    // shift the history one slot back and put this action first
    const int h = weights_->history * kActionDim;
    Eigen::VectorXf hist = input_.segment(d, h);
    input_.segment(d + kActionDim, h - kActionDim) = hist.head(h - kActionDim);
    input_.segment(d, kActionDim) = a.cast<float>();
  }
  return a;
}

std::string MlpPolicy::name() const {
  if (!name_.empty()) return name_;
  return weights_->history > 0 ? "mlp-delay-aware" : "mlp";
}

std::unique_ptr<Policy> MlpPolicy::clone() const { return std::make_unique<MlpPolicy>(weights_, sha256_, name_); }

}  // namespace actionshift::policy
