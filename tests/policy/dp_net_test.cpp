// Diffusion Policy U-Net: finite-difference gradient checks of every layer and of the whole network
// (double precision), and the shapes and parameter count of the paper's configuration
#include "actionshift/core/rng.hpp"
#include "actionshift/policy/detail/dp_layers.hpp"
#include "actionshift/policy/dp.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <vector>

namespace actionshift::policy {
namespace {

using M = DpMat<double>;
using V = DpVec<double>;
namespace nn = dpnn;

constexpr double kStep = 1e-6;

M random_mat(Rng& rng, int r, int c, double scale = 1.0) {
  M m(r, c);
  for (int j = 0; j < c; ++j)
    for (int i = 0; i < r; ++i) m(i, j) = rng.normal(0.0, scale);
  return m;
}
std::vector<double> random_params(Rng& rng, std::int64_t n) {
  std::vector<double> p(static_cast<std::size_t>(n));
  for (auto& v : p) v = rng.normal(0.0, 0.5);
  return p;
}

void expect_close(double analytic, double numeric, const std::string& what) {
  EXPECT_NEAR(analytic, numeric, 1e-6 * (1.0 + std::abs(analytic) + std::abs(numeric))) << what;
}

// loss = <R, f(p, x)> for a fixed random R: checks the analytic d/dp (every parameter) and d/dx
// (every input) of `bwd` against central differences. fwd(p, x) returns y and refreshes the layer's
// cache; bwd(p, dy, g) adds d/dp to g and returns d/dx for the cache of the last fwd.
void check_layer(std::vector<double> p, M x, const std::function<M(const double*, const M&)>& fwd,
                 const std::function<M(const double*, const M&, double*)>& bwd, const std::string& name) {
  Rng rng(7);
  const M y = fwd(p.data(), x);
  const M r = random_mat(rng, static_cast<int>(y.rows()), static_cast<int>(y.cols()));
  std::vector<double> g(p.size(), 0.0);
  const M dx = bwd(p.data(), r, g.data());
  auto loss = [&](const std::vector<double>& pp, const M& xx) { return r.cwiseProduct(fwd(pp.data(), xx)).sum(); };
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double keep = p[i];
    p[i] = keep + kStep;
    const double lp = loss(p, x);
    p[i] = keep - kStep;
    const double lm = loss(p, x);
    p[i] = keep;
    expect_close(g[i], (lp - lm) / (2 * kStep), name + " d/dparam[" + std::to_string(i) + "]");
  }
  ASSERT_EQ(dx.rows(), x.rows());
  ASSERT_EQ(dx.cols(), x.cols());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double keep = x(i);
    x(i) = keep + kStep;
    const double lp = loss(p, x);
    x(i) = keep - kStep;
    const double lm = loss(p, x);
    x(i) = keep;
    expect_close(dx(i), (lp - lm) / (2 * kStep), name + " d/dx[" + std::to_string(i) + "]");
  }
}

TEST(DpLayers, MishGradient) {
  for (double x : {-30.0, -5.0, -1.3, -0.2, 0.0, 0.4, 1.7, 6.0, 19.9, 20.1, 35.0}) {
    const double num = (nn::mish(x + kStep) - nn::mish(x - kStep)) / (2 * kStep);
    expect_close(nn::mish_grad(x), num, "mish'(" + std::to_string(x) + ")");
  }
  EXPECT_NEAR(nn::mish(1.0), 1.0 * std::tanh(std::log1p(std::exp(1.0))), 1e-15);
  EXPECT_NEAR(nn::mish(-1.0), -0.30340146137410895, 1e-12);  // mish(-1) = -tanh(softplus(-1))
}

TEST(DpLayers, LinearGradient) {
  Rng rng(1);
  const nn::Lin l{5, 3, 0, 15};
  V last;
  check_layer(random_params(rng, 18), random_mat(rng, 5, 1),
              [&](const double* p, const M& x) {
                last = x;
                return M(nn::linear_fwd<double>(l, p, last));
              },
              [&](const double* p, const M& dy, double* g) { return M(nn::linear_bwd<double>(l, p, V(dy), last, g)); }, "linear");
}

struct ConvCase {
  int cin, cout, k, stride, pad, len;
};

TEST(DpLayers, Conv1dGradient) {
  // same-padding (the blocks' k=5 and a k=3), the stride-2 down-sampling and the 1x1 residual/final conv
  for (const ConvCase c : {ConvCase{3, 4, 5, 1, 2, 6}, ConvCase{2, 3, 3, 1, 1, 5}, ConvCase{4, 4, 3, 2, 1, 8}, ConvCase{3, 2, 1, 1, 0, 4}}) {
    Rng rng(2);
    const nn::Conv conv{c.cin, c.cout, c.k, c.stride, c.pad, 0, static_cast<std::int64_t>(c.cout) * c.cin * c.k};
    nn::ConvC<double> cache;
    const M x = random_mat(rng, c.cin, c.len);
    const M y = nn::conv_fwd<double>(conv, random_params(rng, conv.b + c.cout).data(), x, cache);
    ASSERT_EQ(y.cols(), (c.len + 2 * c.pad - c.k) / c.stride + 1);
    check_layer(random_params(rng, conv.b + c.cout), x,
                [&](const double* p, const M& xx) { return nn::conv_fwd<double>(conv, p, xx, cache); },
                [&](const double* p, const M& dy, double* g) { return nn::conv_bwd<double>(conv, p, dy, cache, g, true); },
                "conv k" + std::to_string(c.k) + " s" + std::to_string(c.stride));
  }
}

TEST(DpLayers, Conv1dMatchesDirectSum) {
  // y(o, t) = b(o) + sum_{i, j} W(o, i, j) x(i, t*stride + j - pad), W in PyTorch's (out, in, k) layout
  Rng rng(3);
  const nn::Conv conv{3, 2, 3, 2, 1, 0, 18};
  const auto p = random_params(rng, 20);
  const M x = random_mat(rng, 3, 6);
  nn::ConvC<double> cache;
  const M y = nn::conv_fwd<double>(conv, p.data(), x, cache);
  ASSERT_EQ(y.cols(), 3);
  for (int o = 0; o < 2; ++o)
    for (int t = 0; t < 3; ++t) {
      double s = p[static_cast<std::size_t>(18 + o)];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const int u = t * 2 + j - 1;
          if (u >= 0 && u < 6) s += p[static_cast<std::size_t>((o * 3 + i) * 3 + j)] * x(i, u);
        }
      EXPECT_NEAR(y(o, t), s, 1e-12);
    }
}

TEST(DpLayers, ConvTranspose1dGradientAndDirectSum) {
  Rng rng(4);
  const nn::Conv tc{3, 2, 4, 2, 1, 0, 24};  // (in, out, k) weight, the up-sampling layer
  const auto p = random_params(rng, 26);
  const M x = random_mat(rng, 3, 4);
  M cache;
  const M y = nn::tconv_fwd<double>(tc, p.data(), x, cache);
  ASSERT_EQ(y.cols(), 8);  // doubles the length
  // y(o, s*2 - 1 + j) += W(i, o, j) x(i, s)
  M want(2, 8);
  for (int o = 0; o < 2; ++o) want.row(o).setConstant(p[static_cast<std::size_t>(24 + o)]);
  for (int i = 0; i < 3; ++i)
    for (int o = 0; o < 2; ++o)
      for (int j = 0; j < 4; ++j)
        for (int s = 0; s < 4; ++s) {
          const int t = s * 2 - 1 + j;
          if (t >= 0 && t < 8) want(o, t) += p[static_cast<std::size_t>((i * 2 + o) * 4 + j)] * x(i, s);
        }
  EXPECT_LT((y - want).cwiseAbs().maxCoeff(), 1e-12);
  check_layer(p, x, [&](const double* pp, const M& xx) { return nn::tconv_fwd<double>(tc, pp, xx, cache); },
              [&](const double* pp, const M& dy, double* g) { return nn::tconv_bwd<double>(tc, pp, dy, cache, g); }, "conv transpose");
}

TEST(DpLayers, GroupNormGradient) {
  Rng rng(5);
  const nn::Gn gn{6, 3, 0, 6};
  nn::GnC<double> cache;
  const M x = random_mat(rng, 6, 5, 2.0);
  const auto p = random_params(rng, 12);
  const M y = nn::gn_fwd<double>(gn, p.data(), x, cache);
  // with unit weight and zero bias every group has mean 0 and variance var/(var+eps)
  std::vector<double> unit(12, 0.0);
  for (int c = 0; c < 6; ++c) unit[static_cast<std::size_t>(c)] = 1.0;
  const M z = nn::gn_fwd<double>(gn, unit.data(), x, cache);
  for (int g = 0; g < 3; ++g) EXPECT_NEAR(z.middleRows(2 * g, 2).mean(), 0.0, 1e-12);
  EXPECT_EQ(y.rows(), 6);
  check_layer(p, x, [&](const double* pp, const M& xx) { return nn::gn_fwd<double>(gn, pp, xx, cache); },
              [&](const double* pp, const M& dy, double* g) { return nn::gn_bwd<double>(gn, pp, dy, cache, g); }, "groupnorm");
}

TEST(DpLayers, FilmGradient) {
  Rng rng(6);
  const nn::Lin film{5, 8, 0, 40};  // cond 5 -> scale and bias for 4 channels
  const auto p = random_params(rng, 48);
  const V mcond = random_mat(rng, 5, 1);
  V scale;
  M x_keep;
  check_layer(p, random_mat(rng, 4, 3),
              [&](const double* pp, const M& x) {
                x_keep = x;
                return nn::film_fwd<double>(film, pp, x, mcond, scale);
              },
              [&](const double* pp, const M& dy, double* g) {
                V dm = V::Zero(5);
                return nn::film_bwd<double>(film, pp, dy, x_keep, mcond, scale, dm, g);
              },
              "film");
  // d/d(mcond)
  const M x = random_mat(rng, 4, 3);
  const M r = random_mat(rng, 4, 3);
  nn::film_fwd<double>(film, p.data(), x, mcond, scale);
  std::vector<double> g(p.size(), 0.0);
  V dm = V::Zero(5);
  nn::film_bwd<double>(film, p.data(), r, x, mcond, scale, dm, g.data());
  for (int i = 0; i < 5; ++i) {
    V a = mcond, b = mcond;
    a(i) += kStep;
    b(i) -= kStep;
    V s;
    const double num = (r.cwiseProduct(nn::film_fwd<double>(film, p.data(), x, a, s)).sum() -
                        r.cwiseProduct(nn::film_fwd<double>(film, p.data(), x, b, s)).sum()) /
                       (2 * kStep);
    expect_close(dm(i), num, "film d/dcond");
  }
}

// a residual block laid out by hand: block0 (conv k3 + GN), block1, FiLM from a 5-wide condition,
// 1x1 residual conv when the widths differ
nn::Res make_res(int cin, int cout, int groups, std::int64_t& n) {
  auto take = [&n](std::int64_t size) {
    const std::int64_t at = n;
    n += size;
    return at;
  };
  nn::Res r;
  r.cout = cout;
  auto block = [&](int i, int o) {
    nn::Block b;
    b.conv = nn::Conv{i, o, 3, 1, 1, take(static_cast<std::int64_t>(o) * i * 3), take(o)};
    b.gn = nn::Gn{o, groups, take(o), take(o)};
    return b;
  };
  r.b0 = block(cin, cout);
  r.b1 = block(cout, cout);
  r.film = nn::Lin{5, 2 * cout, take(10 * cout), take(2 * cout)};
  r.has_res = cin != cout;
  if (r.has_res) r.res = nn::Conv{cin, cout, 1, 1, 0, take(static_cast<std::int64_t>(cout) * cin), take(cout)};
  return r;
}

TEST(DpLayers, ResidualBlockGradient) {
  for (const auto& [cin, cout] : {std::pair{3, 4}, std::pair{4, 4}}) {
    Rng rng(8);
    std::int64_t n = 0;
    const nn::Res r = make_res(cin, cout, 2, n);
    const V mcond = random_mat(rng, 5, 1);
    nn::ResC<double> cache;
    check_layer(random_params(rng, n), random_mat(rng, cin, 6),
                [&](const double* p, const M& x) { return nn::res_fwd<double>(r, p, x, mcond, cache); },
                [&](const double* p, const M& dy, double* g) {
                  V dm = V::Zero(5);
                  return nn::res_bwd<double>(r, p, dy, mcond, dm, cache, g);
                },
                "residual " + std::to_string(cin) + "->" + std::to_string(cout));
  }
}

DpArch tiny_arch(std::vector<int> down) {
  DpArch a;
  a.action_dim = 3;
  a.obs_dim = 2;
  a.obs_horizon = 2;
  a.pred_horizon = 8;
  a.act_horizon = 4;
  a.step_embed_dim = 8;
  a.down_dims = std::move(down);
  a.kernel_size = 3;
  a.groups = 2;
  return a;
}

// the whole U-Net: every parameter and every input of a tiny 2- and 3-level network
TEST(DpUnet, WholeNetworkGradient) {
  for (const auto& down : {std::vector<int>{4, 6}, std::vector<int>{4, 6, 8}}) {
    const DpArch arch = tiny_arch(down);
    const DpUnet<double> net(arch);
    Rng rng(9);
    std::vector<double> p = net.init(11);
    for (auto& v : p) v += rng.normal(0.0, 0.05);  // GroupNorm weights and biases away from 1 and 0
    const V cond = random_mat(rng, 4, 1);
    auto ws = net.workspace();
    check_layer(p, random_mat(rng, 3, 8),
                [&](const double* pp, const M& x) { return net.forward(pp, x, 37.0, cond, *ws); },
                [&](const double* pp, const M& dy, double* g) {
                  M dx;
                  net.backward(pp, dy, *ws, g, &dx);
                  return dx;
                },
                "unet " + std::to_string(down.size()) + " levels");
  }
}

TEST(DpUnet, FloatMatchesDouble) {
  const DpArch arch = tiny_arch({8, 16});
  const DpUnet<double> nd(arch);
  const DpUnet<float> nf(arch);
  const std::vector<double> pd = nd.init(3);
  const std::vector<float> pf = nf.init(3);
  ASSERT_EQ(pd.size(), pf.size());
  for (std::size_t i = 0; i < pd.size(); ++i) ASSERT_EQ(static_cast<float>(pd[i]), pf[i]);
  Rng rng(4);
  const M x = random_mat(rng, 3, 8);
  const V c = random_mat(rng, 4, 1);
  auto wd = nd.workspace();
  auto wf = nf.workspace();
  const M yd = nd.forward(pd.data(), x, 5.0, c, *wd);
  const DpMat<float> yf = nf.forward(pf.data(), x.cast<float>(), 5.0, c.cast<float>(), *wf);
  EXPECT_LT((yd - yf.cast<double>()).cwiseAbs().maxCoeff(), 1e-4);
}

// Training runs the network on a batch at once (the weight products over the samples' columns side
// by side). Every sample must get the bits it gets alone: the output, d/dx, and the gradient of samples
// sharing a buffer summed in sample order, or the committed .asdp files would not re-train byte for byte.
// The paper's configuration, so the depths Eigen blocks (1,280 and 2,560) and all three lengths (16, 8, 4)
// are exercised, under both L1 sizes that block them differently.
TEST(DpUnet, ABatchGivesEverySampleTheBitsItGetsAlone) {
  const DpUnet<float> net{DpArch{}};
  const std::vector<float> p = net.init(11);
  const std::size_t n = 5;
  Rng rng(12);
  std::vector<DpMat<float>> x(n), dy(n);
  std::vector<DpVec<float>> c(n);
  std::vector<double> steps(n);
  for (std::size_t b = 0; b < n; ++b) {
    x[b] = random_mat(rng, 7, 16).cast<float>();
    dy[b] = random_mat(rng, 7, 16, 0.1).cast<float>();
    c[b] = random_mat(rng, 84, 1).cast<float>();
    steps[b] = static_cast<double>(17 * b);
  }
  const std::ptrdiff_t l1 = Eigen::l1CacheSize(), l2 = Eigen::l2CacheSize(), l3 = Eigen::l3CacheSize();
  for (const std::ptrdiff_t cache : {std::ptrdiff_t{32 * 1024}, std::ptrdiff_t{48 * 1024}}) {
    Eigen::setCpuCacheSizes(cache, l2, l3);
    // one by one: samples 0-2 add to the first gradient, 3-4 to the second
    std::vector<float> g1a(p.size(), 0.0f), g1b(p.size(), 0.0f), g2a(p.size(), 0.0f), g2b(p.size(), 0.0f);
    std::vector<DpMat<float>> y1(n), dx1(n);
    for (std::size_t b = 0; b < n; ++b) {
      auto ws = net.workspace();
      y1[b] = net.forward(p.data(), x[b], steps[b], c[b], *ws);
      net.backward(p.data(), dy[b], *ws, (b < 3 ? g1a : g1b).data(), &dx1[b]);
    }
    std::vector<std::shared_ptr<DpUnet<float>::Workspace>> owned(n);
    std::vector<DpUnet<float>::Workspace*> ws(n);
    for (std::size_t b = 0; b < n; ++b) ws[b] = (owned[b] = net.workspace()).get();
    const std::vector<DpMat<float>> y2 = net.forward(p.data(), x, steps, c, ws);
    const std::vector<float*> g2{g2a.data(), g2a.data(), g2a.data(), g2b.data(), g2b.data()};
    const std::vector<DpMat<float>> dx2 = net.backward(p.data(), dy, ws, g2);
    for (std::size_t b = 0; b < n; ++b) {
      ASSERT_EQ(y2[b].size(), y1[b].size());
      EXPECT_EQ(std::memcmp(y2[b].data(), y1[b].data(), sizeof(float) * static_cast<std::size_t>(y1[b].size())), 0) << "output " << b << ", L1 " << cache;
      ASSERT_EQ(dx2[b].size(), dx1[b].size());
      EXPECT_EQ(std::memcmp(dx2[b].data(), dx1[b].data(), sizeof(float) * static_cast<std::size_t>(dx1[b].size())), 0) << "d/dx " << b << ", L1 " << cache;
    }
    EXPECT_EQ(std::memcmp(g2a.data(), g1a.data(), sizeof(float) * p.size()), 0) << "gradient of samples 0-2, L1 " << cache;
    EXPECT_EQ(std::memcmp(g2b.data(), g1b.data(), sizeof(float) * p.size()), 0) << "gradient of samples 3-4, L1 " << cache;
  }
  Eigen::setCpuCacheSizes(l1, l2, l3);
}

// the paper's configuration (ManiSkill's state Diffusion Policy on PickCube): obs 42 x 2 stacked,
// action 7, horizon 16, step embedding 64, down dims 64/128/256, kernel 5, 8 groups
std::int64_t count_by_formula(int a, int cond, int dsed, const std::vector<int>& dims, int k) {
  auto lin = [](std::int64_t i, std::int64_t o) { return i * o + o; };
  auto conv = [](std::int64_t i, std::int64_t o, std::int64_t kk) { return i * o * kk + o; };
  auto block = [&](std::int64_t i, std::int64_t o) { return conv(i, o, k) + 2 * o; };
  auto res = [&](std::int64_t i, std::int64_t o) { return block(i, o) + block(o, o) + lin(cond, 2 * o) + (i != o ? conv(i, o, 1) : 0); };
  std::int64_t n = lin(dsed, 4 * dsed) + lin(4 * dsed, dsed);
  const int levels = static_cast<int>(dims.size());
  int prev = a;
  for (int l = 0; l < levels; ++l) {
    const int c = dims[static_cast<std::size_t>(l)];
    n += res(prev, c) + res(c, c) + (l + 1 < levels ? conv(c, c, 3) : 0);
    prev = c;
  }
  n += 2 * res(dims.back(), dims.back());
  for (int u = 0; u + 1 < levels; ++u) {
    const int co = dims[static_cast<std::size_t>(levels - 1 - u)], ci = dims[static_cast<std::size_t>(levels - 2 - u)];
    n += res(2 * co, ci) + res(ci, ci) + conv(ci, ci, 4);
  }
  return n + block(dims[0], dims[0]) + conv(dims[0], a, 1);
}

TEST(DpUnet, PaperConfigurationShapesAndParameterCount) {
  const DpArch arch;  // defaults = the paper's configuration
  ASSERT_EQ(arch.obs_dim, 42);
  ASSERT_EQ(arch.cond_dim(), 64 + 84);
  const DpUnet<float> net(arch);
  std::printf("paper configuration (64/128/256): %lld parameters\n", static_cast<long long>(net.parameter_count()));
  EXPECT_EQ(net.parameter_count(), 4391495);
  EXPECT_EQ(net.parameter_count(), count_by_formula(7, 148, 64, {64, 128, 256}, 5));
  std::int64_t sum = 0;
  for (const auto& t : net.tensors()) {
    EXPECT_EQ(t.offset, sum) << t.name;
    sum += t.size();
  }
  EXPECT_EQ(sum, net.parameter_count());
  const std::vector<float> p = net.init(1);
  auto ws = net.workspace();
  const DpMat<float> x = DpMat<float>::Random(7, 16);
  const DpVec<float> c = DpVec<float>::Random(84);
  const DpMat<float> y = net.forward(p.data(), x, 99.0, c, *ws);
  EXPECT_EQ(y.rows(), 7);
  EXPECT_EQ(y.cols(), 16);
  EXPECT_TRUE(y.allFinite());
  std::vector<float> g(p.size(), 0.0f);
  net.backward(p.data(), DpMat<float>::Ones(7, 16), *ws, g.data());
  for (float v : g) ASSERT_TRUE(std::isfinite(v));
  // the scaled variant trained on two cores
  DpArch small = arch;
  small.down_dims = {32, 64, 128};
  std::printf("scaled configuration (32/64/128): %lld parameters\n", static_cast<long long>(dp_parameter_count(small)));
  EXPECT_EQ(dp_parameter_count(small), 1259975);
  EXPECT_EQ(dp_parameter_count(small), count_by_formula(7, 148, 64, {32, 64, 128}, 5));
}

TEST(DpUnet, RejectsBadArchitectures) {
  DpArch a;
  a.down_dims = {64, 100};
  EXPECT_THROW(DpUnet<float>{a}, std::invalid_argument);  // 100 not a multiple of 8 groups
  a = DpArch{};
  a.pred_horizon = 10;  // not a multiple of 4 with three levels
  EXPECT_THROW(DpUnet<float>{a}, std::invalid_argument);
  a = DpArch{};
  a.kernel_size = 4;
  EXPECT_THROW(DpUnet<float>{a}, std::invalid_argument);
  a = DpArch{};
  const DpUnet<float> net(a);
  auto ws = net.workspace();
  const auto p = net.init(1);
  EXPECT_THROW(net.forward(p.data(), DpMat<float>::Zero(7, 8), 0, DpVec<float>::Zero(84), *ws), std::invalid_argument);
}

}  // namespace
}  // namespace actionshift::policy
