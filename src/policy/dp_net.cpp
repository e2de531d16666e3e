// Diffusion Policy: the conditional 1-D U-Net, forward and hand-written backward (dp.hpp)
#include "actionshift/policy/dp.hpp"

#include "actionshift/core/rng.hpp"
#include "actionshift/policy/detail/dp_layers.hpp"

#include <cmath>
#include <stdexcept>

namespace actionshift::policy {

using namespace dpnn;  // NOLINT: the layers of detail/dp_layers.hpp

// ---- architecture ------------------------------------------------------------------------------

void DpArch::validate() const {
  auto bad = [](const std::string& field, const std::string& why) { throw std::invalid_argument("dp architecture: " + field + ": " + why); };
  if (action_dim <= 0) bad("action_dim", "must be positive");
  if (obs_dim <= 0) bad("obs_dim", "must be positive");
  if (obs_horizon <= 0) bad("obs_horizon", "must be positive");
  if (step_embed_dim < 4 || step_embed_dim % 2 != 0) bad("step_embed_dim", "must be even and at least 4");
  if (down_dims.empty()) bad("down_dims", "needs at least one level");
  if (groups <= 0) bad("groups", "must be positive");
  for (int d : down_dims)
    if (d <= 0 || d % groups != 0) bad("down_dims", "every width must be a positive multiple of groups (" + std::to_string(groups) + ")");
  if (kernel_size <= 0 || kernel_size % 2 == 0) bad("kernel_size", "must be odd");
  const int stride = 1 << (down_dims.size() - 1);
  if (pred_horizon <= 0 || pred_horizon % stride != 0)
    bad("pred_horizon", "must be a positive multiple of " + std::to_string(stride) + " (2^(levels-1))");
  if (act_horizon <= 0 || obs_horizon - 1 + act_horizon > pred_horizon)
    bad("act_horizon", "must be positive with obs_horizon - 1 + act_horizon <= pred_horizon");
  if (diffusion_steps <= 0) bad("diffusion_steps", "must be positive");
}

nlohmann::json DpArch::to_json() const {
  return {{"action_dim", action_dim},       {"obs_dim", obs_dim},         {"obs_horizon", obs_horizon},
          {"pred_horizon", pred_horizon},   {"act_horizon", act_horizon}, {"step_embed_dim", step_embed_dim},
          {"down_dims", down_dims},         {"kernel_size", kernel_size}, {"groups", groups},
          {"diffusion_steps", diffusion_steps}};
}

std::int64_t DpTensor::size() const {
  std::int64_t n = 1;
  for (int s : shape) n *= s;
  return n;
}

template <class S>
struct DpUnet<S>::Spec {
  Lin step1, step2;
  std::vector<Res> down;         // 2 per level
  std::vector<Conv> downsample;  // levels - 1
  std::vector<Res> mid;          // 2
  std::vector<Res> up;           // 2 per up level (levels - 1)
  std::vector<TConv> upsample;   // levels - 1
  Block final_block;
  Conv final_conv;
  std::vector<double> init_bound;  // per tensor: uniform bound, or < 0: constant -bound - 1 (GroupNorm)
};

template <class S>
struct DpUnet<S>::Workspace {
  Vec<S> emb, h1, mh1, cond, mcond;
  std::vector<ResC<S>> down, mid, up;
  std::vector<ConvC<S>> downsample;
  std::vector<Mat<S>> upsample;  // inputs of the transposed convolutions
  std::vector<int> up_channels;  // channels of x before the skip is concatenated
  BlockC<S> fin_block;
  ConvC<S> fin_conv;
};

template <class S>
DpUnet<S>::DpUnet(const DpArch& arch) : arch_(arch), spec_(std::make_unique<Spec>()) {
  arch_.validate();
  Spec& sp = *spec_;
  auto add = [&](const std::string& name, std::vector<int> shape, double bound) {
    DpTensor t{name, count_, std::move(shape)};
    count_ += t.size();
    tensors_.push_back(std::move(t));
    sp.init_bound.push_back(bound);
    return tensors_.back().offset;
  };
  auto lin = [&](const std::string& name, int in, int out) {
    Lin l{in, out, 0, 0};
    const double b = 1.0 / std::sqrt(static_cast<double>(in));
    l.w = add(name + ".weight", {out, in}, b);
    l.b = add(name + ".bias", {out}, b);
    return l;
  };
  auto conv = [&](const std::string& name, int cin, int cout, int k, int stride, int pad) {
    Conv c{cin, cout, k, stride, pad, 0, 0};
    const double b = 1.0 / std::sqrt(static_cast<double>(cin * k));
    c.w = add(name + ".weight", {cout, cin, k}, b);
    c.b = add(name + ".bias", {cout}, b);
    return c;
  };
  auto tconv = [&](const std::string& name, int cin, int cout, int k, int stride, int pad) {
    TConv c{cin, cout, k, stride, pad, 0, 0};
    const double b = 1.0 / std::sqrt(static_cast<double>(cout * k));  // PyTorch's fan_in of ConvTranspose1d
    c.w = add(name + ".weight", {cin, cout, k}, b);
    c.b = add(name + ".bias", {cout}, b);
    return c;
  };
  auto block = [&](const std::string& name, int cin, int cout) {
    Block b;
    b.conv = conv(name + ".conv", cin, cout, arch_.kernel_size, 1, arch_.kernel_size / 2);
    b.gn = Gn{cout, arch_.groups, 0, 0};
    b.gn.w = add(name + ".norm.weight", {cout}, -2.0);  // constant 1
    b.gn.b = add(name + ".norm.bias", {cout}, -1.0);    // constant 0
    return b;
  };
  auto res = [&](const std::string& name, int cin, int cout) {
    Res r;
    r.cout = cout;
    r.b0 = block(name + ".block0", cin, cout);
    r.b1 = block(name + ".block1", cout, cout);
    r.film = lin(name + ".film", arch_.cond_dim(), 2 * cout);
    r.has_res = cin != cout;
    if (r.has_res) r.res = conv(name + ".residual", cin, cout, 1, 1, 0);
    return r;
  };
  const int d = arch_.step_embed_dim;
  sp.step1 = lin("step_encoder.0", d, 4 * d);
  sp.step2 = lin("step_encoder.2", 4 * d, d);
  const auto& dims = arch_.down_dims;
  const int levels = static_cast<int>(dims.size());
  for (int l = 0; l < levels; ++l) {
    const int cin = l == 0 ? arch_.action_dim : dims[static_cast<std::size_t>(l - 1)];
    const int c = dims[static_cast<std::size_t>(l)];
    const std::string n = "down." + std::to_string(l);
    sp.down.push_back(res(n + ".0", cin, c));
    sp.down.push_back(res(n + ".1", c, c));
    if (l + 1 < levels) sp.downsample.push_back(conv(n + ".downsample", c, c, 3, 2, 1));
  }
  sp.mid.push_back(res("mid.0", dims.back(), dims.back()));
  sp.mid.push_back(res("mid.1", dims.back(), dims.back()));
  for (int u = 0; u + 1 < levels; ++u) {
    const int cout = dims[static_cast<std::size_t>(levels - 1 - u)];  // channels of x and of the skip
    const int cin = dims[static_cast<std::size_t>(levels - 2 - u)];
    const std::string n = "up." + std::to_string(u);
    sp.up.push_back(res(n + ".0", 2 * cout, cin));
    sp.up.push_back(res(n + ".1", cin, cin));
    sp.upsample.push_back(tconv(n + ".upsample", cin, cin, 4, 2, 1));
  }
  sp.final_block = block("final.block", dims.front(), dims.front());
  sp.final_conv = conv("final.conv", dims.front(), arch_.action_dim, 1, 1, 0);
}

template <class S>
DpUnet<S>::~DpUnet() = default;

template <class S>
DpUnet<S>::DpUnet(const DpUnet& o) : arch_(o.arch_), count_(o.count_), tensors_(o.tensors_), spec_(std::make_unique<Spec>(*o.spec_)) {}

template <class S>
std::vector<S> DpUnet<S>::init(std::uint64_t seed) const {
  std::vector<S> p(static_cast<std::size_t>(count_));
  Rng rng(seed);
  for (std::size_t t = 0; t < tensors_.size(); ++t) {
    const double b = spec_->init_bound[t];
    S* dst = p.data() + tensors_[t].offset;
    for (std::int64_t i = 0; i < tensors_[t].size(); ++i)
      dst[i] = b >= 0 ? static_cast<S>(rng.uniform(-b, b)) : static_cast<S>(-b - 1.0);
  }
  return p;
}

template <class S>
std::shared_ptr<typename DpUnet<S>::Workspace> DpUnet<S>::workspace() const {
  auto ws = std::make_shared<Workspace>();
  ws->down.resize(spec_->down.size());
  ws->mid.resize(spec_->mid.size());
  ws->up.resize(spec_->up.size());
  ws->downsample.resize(spec_->downsample.size());
  ws->upsample.resize(spec_->upsample.size());
  ws->up_channels.resize(spec_->upsample.size());
  return ws;
}

template <class S>
Mat<S> DpUnet<S>::forward(const S* p, const Mat<S>& x_in, double step, const Vec<S>& global_cond, Workspace& ws) const {
  Workspace* w = &ws;
  return std::move(forward(p, Batch<S>{x_in}, {step}, {global_cond}, std::span<Workspace* const>(&w, 1))[0]);
}

template <class S>
void DpUnet<S>::backward(const S* p, const Mat<S>& dy, Workspace& ws, S* g, Mat<S>* dx_out) const {
  Workspace* w = &ws;
  Batch<S> dx = backward(p, Batch<S>{dy}, std::span<Workspace* const>(&w, 1), std::span<S* const>(&g, 1));
  if (dx_out != nullptr) *dx_out = std::move(dx[0]);
}

template <class S>
std::vector<Mat<S>> DpUnet<S>::forward(const S* p, const std::vector<Mat<S>>& x_in, const std::vector<double>& steps,
                                       const std::vector<Vec<S>>& global_cond, std::span<Workspace* const> ws) const {
  const Spec& sp = *spec_;
  const std::size_t n = x_in.size();
  if (steps.size() != n || global_cond.size() != n || ws.size() != n)
    throw std::invalid_argument("DpUnet::forward: one step, condition and workspace per sample");
  const int d = arch_.step_embed_dim, half = d / 2;
  const double scale = std::log(10000.0) / (half - 1);
  for (std::size_t b = 0; b < n; ++b) {
    if (x_in[b].rows() != arch_.action_dim || x_in[b].cols() != arch_.pred_horizon)
      throw std::invalid_argument("DpUnet::forward: x must be " + std::to_string(arch_.action_dim) + " x " + std::to_string(arch_.pred_horizon));
    if (global_cond[b].size() != arch_.obs_horizon * arch_.obs_dim)
      throw std::invalid_argument("DpUnet::forward: global condition must have " + std::to_string(arch_.obs_horizon * arch_.obs_dim) + " entries");
    // sinusoidal step embedding (diffusion_policy's SinusoidalPosEmb)
    Workspace& w = *ws[b];
    w.emb.resize(d);
    for (int i = 0; i < half; ++i) {
      const double a = steps[b] * std::exp(-scale * i);
      w.emb(i) = static_cast<S>(std::sin(a));
      w.emb(half + i) = static_cast<S>(std::cos(a));
    }
    w.h1 = linear_fwd(sp.step1, p, w.emb);
    w.mh1 = mish_of(w.h1);
    w.cond.resize(arch_.cond_dim());
    w.cond.head(d) = linear_fwd(sp.step2, p, w.mh1);
    w.cond.tail(global_cond[b].size()) = global_cond[b];
    w.mcond = mish_of(w.cond);
  }
  auto mcond = [&](std::size_t b) -> const Vec<S>& { return ws[b]->mcond; };
  auto res = [&](const Res& r, const Batch<S>& x, std::vector<ResC<S>> Workspace::*caches, std::size_t i) {
    return res_fwd_each(r, p, x, mcond, [&](std::size_t b) -> ResC<S>& { return ((*ws[b]).*caches)[i]; });
  };

  const int levels = static_cast<int>(arch_.down_dims.size());
  std::vector<Batch<S>> skips;
  Batch<S> x = x_in;
  for (int l = 0; l < levels; ++l) {
    const auto i0 = static_cast<std::size_t>(2 * l);
    x = res(sp.down[i0], x, &Workspace::down, i0);
    x = res(sp.down[i0 + 1], x, &Workspace::down, i0 + 1);
    skips.push_back(x);
    const auto sl = static_cast<std::size_t>(l);
    if (l + 1 < levels) x = conv_fwd_each(sp.downsample[sl], p, x, [&](std::size_t b) -> ConvC<S>& { return ws[b]->downsample[sl]; });
  }
  x = res(sp.mid[0], x, &Workspace::mid, 0);
  x = res(sp.mid[1], x, &Workspace::mid, 1);
  for (int u = 0; u + 1 < levels; ++u) {
    const auto su = static_cast<std::size_t>(u);
    const Batch<S>& skip = skips[static_cast<std::size_t>(levels - 1 - u)];
    for (std::size_t b = 0; b < n; ++b) {
      ws[b]->up_channels[su] = static_cast<int>(x[b].rows());
      Mat<S> cat(x[b].rows() + skip[b].rows(), x[b].cols());
      cat << x[b], skip[b];
      x[b] = std::move(cat);
    }
    x = res(sp.up[2 * su], x, &Workspace::up, 2 * su);
    x = res(sp.up[2 * su + 1], x, &Workspace::up, 2 * su + 1);
    x = tconv_fwd_each(sp.upsample[su], p, x, [&](std::size_t b) -> Mat<S>& { return ws[b]->upsample[su]; });
  }
  x = block_fwd_each(sp.final_block, p, x, [&](std::size_t b) -> BlockC<S>& { return ws[b]->fin_block; });
  return conv_fwd_each(sp.final_conv, p, x, [&](std::size_t b) -> ConvC<S>& { return ws[b]->fin_conv; });
}

template <class S>
std::vector<Mat<S>> DpUnet<S>::backward(const S* p, const std::vector<Mat<S>>& dy, std::span<Workspace* const> ws,
                                        std::span<S* const> grads) const {
  const Spec& sp = *spec_;
  const std::size_t n = dy.size();
  if (ws.size() != n || grads.size() != n) throw std::invalid_argument("DpUnet::backward: one workspace and gradient per sample");
  S* const* g = grads.data();
  const int levels = static_cast<int>(arch_.down_dims.size());
  std::vector<Vec<S>> dmcond(n, Vec<S>::Zero(arch_.cond_dim()));
  auto mcond = [&](std::size_t b) -> const Vec<S>& { return ws[b]->mcond; };
  auto dcond = [&](std::size_t b) -> Vec<S>& { return dmcond[b]; };
  auto res = [&](const Res& r, const Batch<S>& d, std::vector<ResC<S>> Workspace::*caches, std::size_t i) {
    return res_bwd_each(r, p, d, mcond, dcond, [&](std::size_t b) -> const ResC<S>& { return ((*ws[b]).*caches)[i]; }, g);
  };
  Batch<S> d = conv_bwd_each(sp.final_conv, p, dy, [&](std::size_t b) -> const ConvC<S>& { return ws[b]->fin_conv; }, g, true);
  d = block_bwd_each(sp.final_block, p, d, [&](std::size_t b) -> const BlockC<S>& { return ws[b]->fin_block; }, g, true);
  std::vector<Batch<S>> dskip(static_cast<std::size_t>(levels));
  for (int u = levels - 2; u >= 0; --u) {
    const auto su = static_cast<std::size_t>(u);
    d = tconv_bwd_each(sp.upsample[su], p, d, [&](std::size_t b) -> const Mat<S>& { return ws[b]->upsample[su]; }, g);
    d = res(sp.up[2 * su + 1], d, &Workspace::up, 2 * su + 1);
    d = res(sp.up[2 * su], d, &Workspace::up, 2 * su);
    Batch<S>& skip = dskip[static_cast<std::size_t>(levels - 1 - u)];
    skip.resize(n);
    for (std::size_t b = 0; b < n; ++b) {
      const int cx = ws[b]->up_channels[su];
      skip[b] = d[b].bottomRows(d[b].rows() - cx);
      d[b] = Mat<S>(d[b].topRows(cx));
    }
  }
  d = res(sp.mid[1], d, &Workspace::mid, 1);
  d = res(sp.mid[0], d, &Workspace::mid, 0);
  for (int l = levels - 1; l >= 0; --l) {
    const auto sl = static_cast<std::size_t>(l);
    if (l + 1 < levels) d = conv_bwd_each(sp.downsample[sl], p, d, [&](std::size_t b) -> const ConvC<S>& { return ws[b]->downsample[sl]; }, g, true);
    if (!dskip[sl].empty())
      for (std::size_t b = 0; b < n; ++b) d[b] += dskip[sl][b];
    d = res(sp.down[2 * sl + 1], d, &Workspace::down, 2 * sl + 1);
    d = res(sp.down[2 * sl], d, &Workspace::down, 2 * sl);
  }
  // step encoder (the global condition is data: no gradient needed)
  const int sd = arch_.step_embed_dim;
  for (std::size_t b = 0; b < n; ++b) {
    const Workspace& w = *ws[b];
    const Vec<S> dse = dmcond[b].head(sd).cwiseProduct(mish_grad_of(w.cond.head(sd)));
    const Vec<S> dh1 = linear_bwd(sp.step2, p, dse, w.mh1, g[b]).cwiseProduct(mish_grad_of(w.h1));
    linear_bwd(sp.step1, p, dh1, w.emb, g[b]);
  }
  return d;
}

template class DpUnet<float>;
template class DpUnet<double>;

std::int64_t dp_parameter_count(const DpArch& arch) { return DpUnet<float>(arch).parameter_count(); }

void dp_fix_eigen_l1() {
  if (Eigen::l1CacheSize() != kDpEigenL1Bytes) Eigen::setCpuCacheSizes(kDpEigenL1Bytes, Eigen::l2CacheSize(), Eigen::l3CacheSize());
}

}  // namespace actionshift::policy
