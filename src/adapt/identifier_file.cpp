// Identifier weights and their file format (.asid): kinds, initialisation, serialise and parse
#include "actionshift/adapt/identifier.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/weight_file.hpp"
#include "identifier_detail.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace actionshift::adapt {
namespace {

constexpr char kMagic[8] = {'A', 'S', 'I', 'D', 'W', '\0', '\0', '\1'};
constexpr std::uint32_t kFormatVersion = 1;
constexpr int kMaxWidth = 4096;
constexpr int kMaxWindow = 256;
constexpr std::uintmax_t kMaxFileBytes = detail::kMaxIdentifierFileBytes;

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

void save_identifier(const IdentifierWeights& w, const std::string& path) { write_file_atomic(path, serialize_identifier(w)); }

IdentifierWeights load_identifier(const std::string& path) {
  return parse_identifier(weight_file::read(path, kMaxFileBytes, "identifier weight file"), path);
}

}  // namespace actionshift::adapt
