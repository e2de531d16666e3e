// Diffusion Policy: the `.asdp` weight file and the policy (dp.hpp)
#include "actionshift/policy/dp.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/weight_file.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace actionshift::policy {
namespace {

constexpr char kMagic[8] = {'A', 'S', 'D', 'P', 'W', '\0', '\0', '\1'};
constexpr std::uint32_t kFormatVersion = 1;
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 30;
constexpr std::uint64_t kPolicyNoiseStream = 0x6470'706f'6c69'6379ULL;  // "dppolicy"

nlohmann::json scheduler_json(const DpArch& a) {
  return {{"type", "ddpm"}, {"beta_schedule", "squaredcos_cap_v2"}, {"train_steps", a.diffusion_steps},
          {"prediction", "epsilon"}, {"clip_sample", true}};
}
const nlohmann::json kNormalization = {{"obs", "mean_std"}, {"action", "none"}};

}  // namespace

std::string serialize_dp(const DpWeights& w) {
  std::string payload;
  auto put = [&payload](const float* p, std::size_t n) { payload.append(reinterpret_cast<const char*>(p), n * 4); };
  put(w.obs_mean.data(), static_cast<std::size_t>(w.obs_mean.size()));
  put(w.obs_std.data(), static_cast<std::size_t>(w.obs_std.size()));
  put(w.params.data(), w.params.size());
  nlohmann::json h = {{"format", "actionshift-dp"},
                      {"version", kFormatVersion},
                      {"task", std::string(sim::task_name(w.task))},
                      {"obs_dim", w.arch.obs_dim},
                      {"action_dim", w.arch.action_dim},
                      {"arch", w.arch.to_json()},
                      {"scheduler", scheduler_json(w.arch)},
                      {"sampler_ddim_steps", w.ddim_steps},
                      {"normalization", kNormalization},
                      {"weights", "ema"},
                      {"parameters", w.params.size()},
                      {"payload_floats", payload.size() / 4},
                      {"payload_sha256", sha256_hex(payload)},
                      {"training", w.training}};
  return weight_file::frame(std::string_view(kMagic, 8), kFormatVersion, h, payload);
}

DpWeights parse_dp(std::string_view bytes, const std::string& source) {
  auto fail = [&source](const std::string& field, const std::string& reason) { return InputError(source, field, reason); };
  const weight_file::Unframed u =
      weight_file::unframe(bytes, std::string_view(kMagic, 8), kFormatVersion, source, "Diffusion Policy weight file");
  const nlohmann::json& h = u.header;
  auto need_in = [&](const nlohmann::json& obj, const std::string& prefix, const char* key) -> const nlohmann::json& {
    if (!obj.contains(key)) throw fail(prefix + key, "missing");
    return obj.at(key);
  };
  auto need = [&](const char* key) -> const nlohmann::json& { return need_in(h, "header.", key); };
  // a JSON integer in [lo, hi] (nlohmann's get<int>() would convert 1e30 with undefined behaviour)
  auto int_in = [&](const nlohmann::json& v, const std::string& field, int lo, int hi) -> int {
    if (v.is_number_integer()) {
      const bool neg = !v.is_number_unsigned() && v.get<std::int64_t>() < 0;
      const std::int64_t x = neg ? v.get<std::int64_t>() : static_cast<std::int64_t>(std::min<std::uint64_t>(v.get<std::uint64_t>(), 1ULL << 40));
      if (x >= lo && x <= hi) return static_cast<int>(x);
    }
    throw fail(field, "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + v.dump() + ")");
  };
  DpWeights w;
  try {
    if (need("format") != "actionshift-dp") throw fail("header.format", "expected \"actionshift-dp\"");
    try {
      w.task = sim::parse_task(need("task").get<std::string>());
    } catch (const InputError& e) {
      if (e.source() == source) throw;
      throw fail("header.task", e.reason());
    }
    const nlohmann::json& a = need("arch");
    if (!a.is_object()) throw fail("header.arch", "expected an object");
    const std::string p = "header.arch.";
    w.arch.action_dim = int_in(need_in(a, p, "action_dim"), p + "action_dim", 1, 64);
    w.arch.obs_dim = int_in(need_in(a, p, "obs_dim"), p + "obs_dim", 1, 4096);
    w.arch.obs_horizon = int_in(need_in(a, p, "obs_horizon"), p + "obs_horizon", 1, 16);
    w.arch.pred_horizon = int_in(need_in(a, p, "pred_horizon"), p + "pred_horizon", 1, 1024);
    w.arch.act_horizon = int_in(need_in(a, p, "act_horizon"), p + "act_horizon", 1, 1024);
    w.arch.step_embed_dim = int_in(need_in(a, p, "step_embed_dim"), p + "step_embed_dim", 4, 4096);
    w.arch.kernel_size = int_in(need_in(a, p, "kernel_size"), p + "kernel_size", 1, 31);
    w.arch.groups = int_in(need_in(a, p, "groups"), p + "groups", 1, 1024);
    w.arch.diffusion_steps = int_in(need_in(a, p, "diffusion_steps"), p + "diffusion_steps", 1, 10000);
    const nlohmann::json& dims = need_in(a, p, "down_dims");
    if (!dims.is_array() || dims.empty() || dims.size() > 6) throw fail(p + "down_dims", "expected a list of 1 to 6 widths");
    w.arch.down_dims.clear();
    for (const auto& d : dims) w.arch.down_dims.push_back(int_in(d, p + "down_dims", 1, 4096));
    w.ddim_steps = int_in(need("sampler_ddim_steps"), "header.sampler_ddim_steps", 0, 10000);
    if (h.contains("training")) w.training = h.at("training");
  } catch (const nlohmann::json::exception& e) {
    throw fail("header", std::string("wrong field type: ") + e.what());
  }
  try {
    w.arch.validate();
  } catch (const std::invalid_argument& e) {
    throw fail("header.arch", e.what());
  }
  const int obs_dim = sim::observation_layout(w.task).size();
  if (w.arch.obs_dim != obs_dim)
    throw fail("header.arch.obs_dim", std::to_string(w.arch.obs_dim) + " does not match task " + std::string(sim::task_name(w.task)) +
                                          " (expected " + std::to_string(obs_dim) + ")");
  if (w.arch.action_dim != kActionDim) throw fail("header.arch.action_dim", std::to_string(w.arch.action_dim) + " (expected 7)");
  if (w.ddim_steps > w.arch.diffusion_steps)
    throw fail("header.sampler_ddim_steps", "more DDIM steps than diffusion steps (" + std::to_string(w.arch.diffusion_steps) + ")");
  const std::int64_t params = dp_parameter_count(w.arch);
  const std::int64_t floats = 2 * static_cast<std::int64_t>(obs_dim) + params;
  auto expect = [&](const char* key, const nlohmann::json& want) {
    const nlohmann::json& got = need(key);
    if (got != want) throw fail(std::string("header.") + key, "expected " + want.dump() + " (got " + got.dump() + ")");
  };
  expect("version", kFormatVersion);
  expect("obs_dim", obs_dim);
  expect("action_dim", kActionDim);
  expect("scheduler", scheduler_json(w.arch));
  expect("normalization", kNormalization);
  expect("weights", "ema");
  expect("parameters", params);
  expect("payload_floats", floats);
  weight_file::check_payload(u, floats, source, true, " for the architecture of the header");
  const char* at = u.payload.data();
  w.obs_mean.resize(obs_dim);
  w.obs_std.resize(obs_dim);
  w.params.resize(static_cast<std::size_t>(params));
  std::memcpy(w.obs_mean.data(), at, static_cast<std::size_t>(obs_dim) * 4);
  std::memcpy(w.obs_std.data(), at + static_cast<std::size_t>(obs_dim) * 4, static_cast<std::size_t>(obs_dim) * 4);
  std::memcpy(w.params.data(), at + static_cast<std::size_t>(obs_dim) * 8, w.params.size() * 4);
  if (!w.obs_mean.allFinite() || !w.obs_std.allFinite() || !(w.obs_std.array() > 0.0f).all())
    throw fail("payload", "non-finite observation mean or non-positive observation std");
  if (!std::all_of(w.params.begin(), w.params.end(), [](float v) { return std::isfinite(v); })) throw fail("payload", "non-finite weight");
  return w;
}

void save_dp(const DpWeights& w, const std::string& path) { write_file_atomic(path, serialize_dp(w)); }

DpWeights load_dp(const std::string& path) { return parse_dp(weight_file::read(path, kMaxFileBytes, "weight file"), path); }

// ---- policy --------------------------------------------------------------------------------------

DpPolicy::DpPolicy(std::shared_ptr<const DpWeights> weights, std::string sha256, std::string name)
    : weights_(std::move(weights)),
      sha256_(std::move(sha256)),
      name_(std::move(name)),
      net_(std::make_shared<const DpUnet<float>>(weights_->arch)),
      ws_(net_->workspace()),
      schedule_(DdpmSchedule::squaredcos_cap_v2(weights_->arch.diffusion_steps)) {
  dp_fix_eigen_l1();  // before the worker threads that clone this policy start sampling
  if (static_cast<std::int64_t>(weights_->params.size()) != net_->parameter_count())
    throw std::invalid_argument("DpPolicy: weights do not match the architecture");
}

std::unique_ptr<DpPolicy> DpPolicy::from_file(const std::string& path, std::string name) {
  const std::string bytes = weight_file::read(path, kMaxFileBytes, "weight file");
  auto w = std::make_shared<const DpWeights>(parse_dp(bytes, path));
  return std::make_unique<DpPolicy>(std::move(w), sha256_hex(bytes), name.empty() ? "dp:" + path : std::move(name));
}

void DpPolicy::reset() {
  fresh_ = true;
  frames_.clear();
  next_ = 0;
  chunk_index_ = 0;
}

void DpPolicy::plan() {
  const DpArch& a = weights_->arch;
  cond_.resize(a.obs_horizon * a.obs_dim);
  for (int i = 0; i < a.obs_horizon; ++i) cond_.segment(i * a.obs_dim, a.obs_dim) = frames_[static_cast<std::size_t>(i)];
  Rng rng(derive_seed({kPolicyNoiseStream, episode_seed_, chunk_index_++}));
  dp_fix_eigen_l1();  // a no-op unless something changed Eigen's setting since construction
  chunk_ = dp_sample(*net_, weights_->params.data(), schedule_, cond_, rng, *ws_, weights_->ddim_steps);
  next_ = 0;
  ++chunks_;
}

Action DpPolicy::act(const Eigen::Ref<const Eigen::VectorXd>& obs) {
  check_observation(obs, weights_->task);
  const DpArch& a = weights_->arch;
  const Eigen::VectorXf x = (obs.cast<float>() - weights_->obs_mean).cwiseQuotient(weights_->obs_std);
  if (fresh_) {
    // the stack starts as copies of the reset frame; the episode's noise is seeded by that frame
    frames_.assign(static_cast<std::size_t>(a.obs_horizon), x);
    std::uint64_t seed = 0x6570'6973'6f64'6500ULL;
    for (Eigen::Index i = 0; i < obs.size(); ++i) seed = splitmix64(seed ^ std::bit_cast<std::uint64_t>(obs(i)));
    episode_seed_ = seed;
    fresh_ = false;
    plan();
  } else {
    frames_.erase(frames_.begin());
    frames_.push_back(x);
    if (next_ >= a.act_horizon) plan();
  }
  const Eigen::VectorXf col = chunk_.col(a.obs_horizon - 1 + next_++);
  return col.cast<double>().cwiseMax(-1.0).cwiseMin(1.0);
}

std::unique_ptr<Policy> DpPolicy::clone() const { return std::make_unique<DpPolicy>(weights_, sha256_, name_); }

}  // namespace actionshift::policy
