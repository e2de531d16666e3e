// The unprivileged tier: learned contract identifiers (weights, inference, the acting adapter)
#include "actionshift/adapt/identifier.hpp"

#include "actionshift/core/decoder.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/transforms.hpp"
#include "actionshift/core/weight_file.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace actionshift::adapt {
namespace {

constexpr char kMagic[8] = {'A', 'S', 'I', 'D', 'W', '\0', '\0', '\1'};
constexpr std::uint32_t kFormatVersion = 1;
constexpr int kMaxWidth = 4096;
constexpr int kMaxWindow = 256;
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 28;

static_assert(std::endian::native == std::endian::little, "the .asid reader assumes a little-endian host");


using RowMajor = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

std::string payload_bytes(const IdentifierWeights& w) {
  std::string out;
  auto put = [&out](const float* p, Eigen::Index n) { out.append(reinterpret_cast<const char*>(p), static_cast<std::size_t>(n) * 4); };
  put(w.feature_mean.data(), w.feature_mean.size());
  put(w.feature_std.data(), w.feature_std.size());
  if (w.recurrent > 0) {
    const RowMajor wx = w.wx, wh = w.wh;
    put(wx.data(), wx.size());
    put(wh.data(), wh.size());
    put(w.bh.data(), w.bh.size());
  }
  for (std::size_t i = 0; i < w.w.size(); ++i) {
    const RowMajor rm = w.w[i];
    put(rm.data(), rm.size());
    put(w.b[i].data(), w.b[i].size());
  }
  return out;
}

std::int64_t readout_count(const std::vector<int>& layers) {
  std::int64_t n = 0;
  for (std::size_t i = 0; i + 1 < layers.size(); ++i) n += static_cast<std::int64_t>(layers[i]) * layers[i + 1] + layers[i + 1];
  return n;
}

std::int64_t recurrent_count(int hr) { return static_cast<std::int64_t>(hr) * kStepFeatures + static_cast<std::int64_t>(hr) * hr + hr; }

int argmax(const Eigen::Ref<const Eigen::VectorXf>& v, int start, int n) {
  int best = 0;
  for (int k = 1; k < n; ++k)
    if (v[start + k] > v[start + best]) best = k;
  return best;
}

}  // namespace

const char* identifier_kind_name(IdentifierKind k) {
  switch (k) {
    case IdentifierKind::kOsi: return "osi";
    case IdentifierKind::kProbeOsi: return "probe_osi";
    case IdentifierKind::kRecurrentOsi: return "recurrent_osi";
  }
  return "osi";
}

std::optional<IdentifierKind> parse_identifier_kind(std::string_view name) {
  if (name == "osi") return IdentifierKind::kOsi;
  if (name == "probe_osi") return IdentifierKind::kProbeOsi;
  if (name == "recurrent_osi") return IdentifierKind::kRecurrentOsi;
  return std::nullopt;
}

FieldLabels FieldLabels::of(const Contract& c) {
  FieldLabels l;
  for (int i = 0; i < kPoseDim; ++i) {
    const auto k = static_cast<std::size_t>(i);
    l.permutation[k] = c.permutation()[k];
    l.sign[k] = c.sign()[k] > 0 ? 1 : 0;
    int s = 0;
    for (int g = 0; g < static_cast<int>(grammar::kScaleGrid.size()); ++g)
      if (std::abs(c.scale()[k] - grammar::kScaleGrid[static_cast<std::size_t>(g)]) <
          std::abs(c.scale()[k] - grammar::kScaleGrid[static_cast<std::size_t>(s)]))
        s = g;
    l.scale[k] = s;
  }
  l.target = c.target() == Target::kAbsolute ? 1 : 0;
  l.frame = c.frame() == Frame::kTool ? 1 : 0;
  int lag = 0;
  for (int g = 0; g < static_cast<int>(grammar::kLagGrid.size()); ++g)
    if (std::abs(c.lag() - grammar::kLagGrid[static_cast<std::size_t>(g)]) < std::abs(c.lag() - grammar::kLagGrid[static_cast<std::size_t>(lag)]))
      lag = g;
  l.lag = lag;
  l.gripper = c.gripper_inverted() ? 1 : 0;
  return l;
}

std::array<double, 7> field_agreement(const Contract& p, const Contract& t) {
  std::array<double, 7> a{};
  for (int i = 0; i < kPoseDim; ++i) {
    const auto k = static_cast<std::size_t>(i);
    a[0] += p.permutation()[k] == t.permutation()[k] ? 1.0 / kPoseDim : 0.0;
    a[1] += p.sign()[k] == t.sign()[k] ? 1.0 / kPoseDim : 0.0;
    a[2] += p.scale()[k] == t.scale()[k] ? 1.0 / kPoseDim : 0.0;
  }
  a[3] = p.target() == t.target() ? 1.0 : 0.0;
  a[4] = p.frame() == t.frame() ? 1.0 : 0.0;
  a[5] = p.lag() == t.lag() ? 1.0 : 0.0;
  a[6] = p.gripper_inverted() == t.gripper_inverted() ? 1.0 : 0.0;
  return a;
}

Contract decode_logits(const Eigen::Ref<const Eigen::VectorXf>& z) {
  if (z.size() != heads::kOutputs) throw std::invalid_argument("decode_logits: expected 100 logits");
  ContractFields f;
  // permutation: per-row softmax, then greedy conflict-free assignment
  std::array<std::array<double, kPoseDim>, kPoseDim> prob{};
  for (int i = 0; i < kPoseDim; ++i) {
    const int o = heads::kPermutation + kPoseDim * i;
    const float m = z.segment(o, kPoseDim).maxCoeff();
    double sum = 0.0;
    for (int j = 0; j < kPoseDim; ++j) sum += prob[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = std::exp(static_cast<double>(z[o + j] - m));
    for (auto& p : prob[static_cast<std::size_t>(i)]) p /= sum;
  }
  std::array<int, kPoseDim> order{0, 1, 2, 3, 4, 5};
  auto row_max = [&](int i) { return *std::max_element(prob[static_cast<std::size_t>(i)].begin(), prob[static_cast<std::size_t>(i)].end()); };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return row_max(a) > row_max(b); });
  std::array<bool, kPoseDim> used{};
  for (int i : order) {
    int best = -1;
    for (int j = 0; j < kPoseDim; ++j)
      if (!used[static_cast<std::size_t>(j)] && (best < 0 || prob[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] > prob[static_cast<std::size_t>(i)][static_cast<std::size_t>(best)]))
        best = j;
    used[static_cast<std::size_t>(best)] = true;
    f.permutation[static_cast<std::size_t>(i)] = best;
  }
  for (int i = 0; i < kPoseDim; ++i) {
    const auto k = static_cast<std::size_t>(i);
    f.sign[k] = argmax(z, heads::kSign + 2 * i, 2) == 1 ? 1 : -1;
    f.scale[k] = grammar::kScaleGrid[static_cast<std::size_t>(argmax(z, heads::kScale + 7 * i, 7))];
  }
  f.target = argmax(z, heads::kTarget, 2) == 1 ? "absolute" : "delta";
  f.frame = argmax(z, heads::kFrame, 2) == 1 ? "tool" : "base";
  f.lag = grammar::kLagGrid[static_cast<std::size_t>(argmax(z, heads::kLag, 4))];
  f.gripper_inverted = argmax(z, heads::kGripper, 2) == 1;
  return Contract::make(f);
}

std::int64_t IdentifierWeights::parameter_count() const { return readout_count(layers) + (recurrent > 0 ? recurrent_count(recurrent) : 0); }

IdentifierWeights IdentifierWeights::init(IdentifierKind kind, std::string task, int window, int recurrent,
                                          const std::vector<int>& hidden, std::uint64_t seed) {
  if ((window > 0) == (recurrent > 0)) throw std::invalid_argument("identifier: exactly one of window and recurrent must be positive");
  IdentifierWeights m;
  m.kind = kind;
  m.task = std::move(task);
  m.window = window;
  m.recurrent = recurrent;
  m.feature_mean = Eigen::VectorXf::Zero(kStepFeatures);
  m.feature_std = Eigen::VectorXf::Ones(kStepFeatures);
  Rng rng(seed);
  auto xavier = [&rng](int out, int in) {
    const double limit = std::sqrt(6.0 / (in + out));
    Eigen::MatrixXf w(out, in);
    for (int r = 0; r < out; ++r)
      for (int c = 0; c < in; ++c) w(r, c) = static_cast<float>(rng.uniform(-limit, limit));
    return w;
  };
  if (recurrent > 0) {
    m.wx = xavier(recurrent, kStepFeatures);
    m.wh = xavier(recurrent, recurrent);
    m.bh = Eigen::VectorXf::Zero(recurrent);
  }
  m.layers.push_back(recurrent > 0 ? recurrent : window * kStepFeatures);
  for (int h : hidden) m.layers.push_back(h);
  m.layers.push_back(heads::kOutputs);
  for (std::size_t i = 0; i + 1 < m.layers.size(); ++i) {
    m.w.push_back(xavier(m.layers[i + 1], m.layers[i]));
    m.b.push_back(Eigen::VectorXf::Zero(m.layers[i + 1]));
  }
  return m;
}

std::string serialize_identifier(const IdentifierWeights& w) {
  const std::string payload = payload_bytes(w);
  nlohmann::json h = {{"format", "actionshift-identifier"},
                      {"version", kFormatVersion},
                      {"kind", identifier_kind_name(w.kind)},
                      {"task", w.task},
                      {"window", w.window},
                      {"recurrent", w.recurrent},
                      {"step_features", kStepFeatures},
                      {"layers", w.layers},
                      {"activation", "tanh"},
                      {"heads", "permutation 6x6, sign 6x2, scale 6x7, target 2, frame 2, lag 4, gripper 2"},
                      {"parameters", w.parameter_count()},
                      {"payload_floats", payload.size() / 4},
                      {"payload_sha256", sha256_hex(payload)},
                      {"training", w.training}};
  return weight_file::frame(std::string_view(kMagic, 8), kFormatVersion, h, payload);
}

IdentifierWeights parse_identifier(std::string_view bytes, const std::string& source) {
  auto fail = [&source](const std::string& field, const std::string& reason) { return InputError(source, field, reason); };
  const weight_file::Unframed u = weight_file::unframe(bytes, std::string_view(kMagic, 8), kFormatVersion, source, "identifier weight file");
  const nlohmann::json& h = u.header;
  auto need = [&](const char* key) -> const nlohmann::json& {
    if (!h.contains(key)) throw fail(std::string("header.") + key, "missing");
    return h.at(key);
  };
  auto small_int = [&](const nlohmann::json& v, const std::string& field, int lo, int hi) -> int {
    if (!v.is_number_integer()) throw fail(field, "expected an integer (got " + v.dump() + ")");
    const bool fits = v.is_number_unsigned() ? v.get<std::uint64_t>() <= static_cast<std::uint64_t>(hi)
                                             : v.get<std::int64_t>() >= lo && v.get<std::int64_t>() <= hi;
    if (!fits) throw fail(field, "out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + v.dump() + ")");
    return static_cast<int>(v.get<std::int64_t>());
  };
  IdentifierWeights w;
  if (need("format") != "actionshift-identifier") throw fail("header.format", "expected \"actionshift-identifier\"");
  const auto& kind = need("kind");
  if (!kind.is_string() || !parse_identifier_kind(kind.get<std::string>()))
    throw fail("header.kind", "must be osi, probe_osi or recurrent_osi (got " + kind.dump() + ")");
  w.kind = *parse_identifier_kind(kind.get<std::string>());
  if (!need("task").is_string()) throw fail("header.task", "must be a string");
  w.task = h.at("task").get<std::string>();
  w.window = small_int(need("window"), "header.window", 0, kMaxWindow);
  w.recurrent = small_int(need("recurrent"), "header.recurrent", 0, kMaxWidth);
  if ((w.window > 0) == (w.recurrent > 0)) throw fail("header.window", "exactly one of window and recurrent must be positive");
  if ((w.kind == IdentifierKind::kRecurrentOsi) != (w.recurrent > 0))
    throw fail("header.recurrent", "recurrent_osi needs recurrent > 0, the feed-forward kinds window > 0");
  const auto& layers = need("layers");
  if (!layers.is_array()) throw fail("header.layers", "expected a list of integers");
  for (const auto& n : layers) w.layers.push_back(small_int(n, "header.layers", 1, kMaxWidth));
  if (w.layers.size() < 2) throw fail("header.layers", "needs at least an input and an output size");
  const int expected_in = w.recurrent > 0 ? w.recurrent : w.window * kStepFeatures;
  if (w.layers.front() != expected_in)
    throw fail("header.layers", "input size " + std::to_string(w.layers.front()) + " (expected " + std::to_string(expected_in) + ")");
  if (w.layers.back() != heads::kOutputs)
    throw fail("header.layers", "output size " + std::to_string(w.layers.back()) + " (expected 100)");
  if (h.contains("training")) w.training = h.at("training");
  const std::int64_t floats = 2 * kStepFeatures + w.parameter_count();
  weight_file::check_payload(u, floats, source, true);
  const std::string_view payload = u.payload;
  std::size_t at = 0;
  auto take = [&](float* dst, std::int64_t n) {
    std::memcpy(dst, payload.data() + at, static_cast<std::size_t>(n) * 4);
    at += static_cast<std::size_t>(n) * 4;
  };
  w.feature_mean.resize(kStepFeatures);
  w.feature_std.resize(kStepFeatures);
  take(w.feature_mean.data(), kStepFeatures);
  take(w.feature_std.data(), kStepFeatures);
  if (w.recurrent > 0) {
    RowMajor wx(w.recurrent, kStepFeatures), wh(w.recurrent, w.recurrent);
    take(wx.data(), wx.size());
    take(wh.data(), wh.size());
    w.wx = wx;
    w.wh = wh;
    w.bh.resize(w.recurrent);
    take(w.bh.data(), w.recurrent);
  }
  for (std::size_t i = 0; i + 1 < w.layers.size(); ++i) {
    RowMajor rm(w.layers[i + 1], w.layers[i]);
    take(rm.data(), rm.size());
    w.w.emplace_back(rm);
    Eigen::VectorXf b(w.layers[i + 1]);
    take(b.data(), b.size());
    w.b.push_back(b);
  }
  bool ok = w.feature_mean.allFinite() && w.feature_std.allFinite() && (w.feature_std.array() > 0.0f).all();
  if (w.recurrent > 0) ok = ok && w.wx.allFinite() && w.wh.allFinite() && w.bh.allFinite();
  for (std::size_t i = 0; i < w.w.size(); ++i) ok = ok && w.w[i].allFinite() && w.b[i].allFinite();
  if (!ok) throw fail("payload", "non-finite weight or non-positive feature_std");
  return w;
}

void save_identifier(const IdentifierWeights& w, const std::string& path) { weight_file::write_atomic(path, serialize_identifier(w)); }

IdentifierWeights load_identifier(const std::string& path) {
  return parse_identifier(weight_file::read(path, kMaxFileBytes, "identifier weight file"), path);
}

std::string default_identifiers_dir() {
  if (const char* env = std::getenv("ACTIONSHIFT_IDENTIFIERS_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  if (std::filesystem::is_directory(ACTIONSHIFT_DEFAULT_IDENTIFIERS_DIR, ec)) return ACTIONSHIFT_DEFAULT_IDENTIFIERS_DIR;
  return ACTIONSHIFT_INSTALLED_IDENTIFIERS_DIR;
}

std::string identifier_weights_path(const std::string& weights, IdentifierKind kind, const std::string& dir) {
  if (weights.find('/') != std::string::npos || weights.ends_with(".asid")) return weights;
  return (dir.empty() ? default_identifiers_dir() : dir) + "/" + weights + "." + identifier_kind_name(kind) + ".asid";
}

std::shared_ptr<const IdentifierWeights> load_identifier_cached(const std::string& path, IdentifierKind kind) {
  static std::mutex mu;
  static std::map<std::string, std::shared_ptr<const IdentifierWeights>> cache;
  std::lock_guard<std::mutex> lock(mu);
  auto check_kind = [&](const std::shared_ptr<const IdentifierWeights>& w) {
    if (w->kind != kind)
      throw InputError(path, "header.kind", std::string("holds a ") + identifier_kind_name(w->kind) + " network, not " + identifier_kind_name(kind));
    return w;
  };
  if (auto it = cache.find(path); it != cache.end()) return check_kind(it->second);
  const std::string bytes = weight_file::read(path, kMaxFileBytes, "identifier weight file");
  // a committed file is pinned by its directory's SHA256SUMS
  const std::filesystem::path p(path);
  const std::filesystem::path sums = p.parent_path() / "SHA256SUMS";
  std::error_code ec;
  if (std::filesystem::is_regular_file(sums, ec)) {
    std::istringstream in(read_input_file(sums.string(), "a SHA256SUMS file", kMaxSmallFileBytes));
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::string hash, name;
      ls >> hash >> name;
      if (!name.empty() && name[0] == '*') name.erase(0, 1);
      if (name == p.filename().string() && hash != sha256_hex(bytes))
        throw InputError(path, "sha256", "is " + sha256_hex(bytes) + " but " + sums.string() + " lists " + hash);
    }
  }
  auto w = std::make_shared<const IdentifierWeights>(parse_identifier(bytes, path));
  cache.emplace(path, w);
  return check_kind(w);
}

Eigen::VectorXf identifier_features(const IdentifierWeights& w, const Pose6& raw, const Pose6& response) {
  Eigen::VectorXf x(kStepFeatures);
  x.head<6>() = raw.cast<float>();
  x.tail<6>() = response.cast<float>();
  return (x - w.feature_mean).cwiseQuotient(w.feature_std);
}

IdentifierState::IdentifierState(std::shared_ptr<const IdentifierWeights> w) : w_(std::move(w)) {
  if (!w_) throw std::invalid_argument("IdentifierState: no weights");
  reset();
}

void IdentifierState::reset() {
  steps_ = 0;
  window_ = Eigen::VectorXf::Zero(std::max(w_->window, 0) * kStepFeatures);
  h_ = Eigen::VectorXf::Zero(std::max(w_->recurrent, 0));
}

void IdentifierState::feed(const Pose6& raw, const Pose6& response) { feed_normalised(identifier_features(*w_, raw, response)); }

void IdentifierState::feed_normalised(const Eigen::Ref<const Eigen::VectorXf>& x) {
  ++steps_;
  if (w_->recurrent > 0) {
    h_ = (w_->wx * x + w_->wh * h_ + w_->bh).array().tanh().matrix();
  } else {
    const Eigen::Index n = window_.size();
    if (n > kStepFeatures) window_.head(n - kStepFeatures) = window_.tail(n - kStepFeatures).eval();
    window_.tail(kStepFeatures) = x;
  }
}

Eigen::VectorXf IdentifierState::logits() const {
  Eigen::VectorXf h = w_->recurrent > 0 ? h_ : window_;
  for (std::size_t i = 0; i < w_->w.size(); ++i) {
    Eigen::VectorXf z = w_->w[i] * h + w_->b[i];
    h = i + 1 < w_->w.size() ? Eigen::VectorXf(z.array().tanh()) : z;
  }
  return h;
}

IdentifierAdapter::IdentifierAdapter(std::shared_ptr<const IdentifierWeights> weights, IdentifierOptions options)
    : state_(std::move(weights)), options_(options) {
  sent_.reserve(64);
}

void IdentifierAdapter::begin_episode(std::uint64_t) {
  state_.reset();
  step_ = 0;
  estimate_.reset();
  sent_.clear();
  replica_.reset();
  last_ = {};
}

Action IdentifierAdapter::encode(const Action& canonical, const Mat3& R) {
  last_ = {};
  if (step_ < options_.probe_budget) {  // the fixed pulses of the belief methods: +a on channel k, gripper never actuated
    Action a = Action::Zero();
    a[step_ % kPoseDim] = (step_ / kPoseDim) % 2 == 0 ? options_.probe_amplitude : -options_.probe_amplitude;
    last_.probe = true;
    return a;
  }
  if (!estimate_) return canonical;  // pass-through evidence before the first estimate
  return actionshift::encode(*estimate_, canonical, R, replica_->tracked_target());
}

void IdentifierAdapter::re_estimate() {
  const Contract c = decode_logits(state_.logits());
  if (!estimate_ || !(c == *estimate_)) {
    estimate_ = c;
    replica_.emplace(c);  // the tracked target the wrapper holds if the estimate is the truth
    for (const auto& [raw, R] : sent_) replica_->step(raw, R);
  }
}

void IdentifierAdapter::observe(const Action& raw, const Pose6& response, const Mat3& R) {
  state_.feed(raw.head<6>(), response);
  sent_.emplace_back(raw, R);
  ++step_;
  if (replica_) replica_->step(raw, R);
  const int first = options_.probe_budget + options_.warmup;
  if (step_ < first) return;
  if (options_.freeze && estimate_) return;
  re_estimate();
}

}  // namespace actionshift::adapt
