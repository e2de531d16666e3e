#pragma once
/// \file
/// Layers of the Diffusion Policy U-Net (dp.hpp) with their hand-written backward passes, for one
/// sample (channels x time, column-major). Parameters are read from and gradients added to flat
/// arrays at the offsets of the layer descriptors; tensors keep PyTorch's layouts (Linear (out, in),
/// Conv1d (out, in, k), ConvTranspose1d (in, out, k), row-major). Implementation detail of
/// dp_net.cpp, public so the tests can check every layer's gradient on its own.

#include "actionshift/policy/dp.hpp"

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace actionshift::policy::dpnn {

inline constexpr double kGroupNormEps = 1e-5;

template <class S>
using Mat = DpMat<S>;
template <class S>
using Vec = DpVec<S>;
template <class S>
using RowMat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
template <class S>
using CRowMap = Eigen::Map<const RowMat<S>>;
template <class S>
using RowMap = Eigen::Map<RowMat<S>>;
template <class S>
using CVecMap = Eigen::Map<const Vec<S>>;
template <class S>
using VecMap = Eigen::Map<Vec<S>>;

// layer descriptors: sizes and offsets into the flat parameter vector
struct Conv {
  int cin{0}, cout{0}, k{1}, stride{1}, pad{0};
  std::int64_t w{0}, b{0};
};
using TConv = Conv;  // ConvTranspose1d: weight (cin, cout, k)
struct Lin {
  int in{0}, out{0};
  std::int64_t w{0}, b{0};
};
struct Gn {
  int c{0}, groups{1};
  std::int64_t w{0}, b{0};
};
struct Block {  // Conv1d - GroupNorm - Mish
  Conv conv;
  Gn gn;
};
struct Res {  // conditional residual block
  Block b0, b1;
  Lin film;
  bool has_res{false};
  Conv res;
  int cout{0};
};

// ---- elementwise -------------------------------------------------------------------------------

template <class S>
S softplus(S x) {
  return x > S(20) ? x : std::log1p(std::exp(x));  // PyTorch's threshold
}
template <class S>
S mish(S x) {
  return x * std::tanh(softplus(x));
}
// d mish / dx given tn = tanh(softplus(x)), which the forward pass keeps
template <class S>
S mish_grad_tn(S x, S tn) {
  const S sig = S(1) / (S(1) + std::exp(-x));
  return tn + x * (S(1) - tn * tn) * sig;
}
template <class S>
S mish_grad(S x) {
  return mish_grad_tn(x, std::tanh(softplus(x)));
}
template <class Derived>
auto mish_of(const Eigen::MatrixBase<Derived>& x) {
  using S = typename Derived::Scalar;
  return x.unaryExpr([](S v) { return mish(v); }).eval();
}
template <class Derived>
auto mish_grad_of(const Eigen::MatrixBase<Derived>& x) {
  using S = typename Derived::Scalar;
  return x.unaryExpr([](S v) { return mish_grad(v); }).eval();
}

// ---- caches ------------------------------------------------------------------------------------

template <class S>
struct ConvC {
  Mat<S> xcol;  // im2col of the input: (cin * k) x lout
  int lin{0};
};
template <class S>
struct GnC {
  Mat<S> xhat;
  Vec<S> rstd;
};
template <class S>
struct BlockC {
  ConvC<S> conv;
  GnC<S> gn;
  Mat<S> pre;  // GroupNorm output = Mish input
  Mat<S> tn;   // tanh(softplus(pre)): Mish is pre * tn, and its derivative reuses tn
};
template <class S>
struct ResC {
  BlockC<S> b0, b1;
  Mat<S> out1;
  Vec<S> scale;
  ConvC<S> res;
};

// ---- batches -----------------------------------------------------------------------------------
//
// Training runs every layer on a batch of samples at once, so the weights are packed for Eigen's
// matrix product once per batch instead of once per sample. Only the products whose left operand is
// a weight matrix are batched: their right operands (one per sample) are placed side by side and
// multiplied in one product. Eigen's product computes every column of the result from that column
// alone, with a blocking of the depth that depends on the depth (and the L1 cache size) only, so each
// sample gets the same bits as its own product (tests/policy/dp_net_test.cpp checks it, and the
// committed .asdp files re-train byte for byte). Everything else (GroupNorm, FiLM, Mish, the weight
// gradients, which are summed in sample order) runs sample by sample as before. A single sample is a
// batch of one.

template <class S>
using Batch = std::vector<Mat<S>>;

// a * x(b) for every sample b in [0, n), as one product over the samples' columns side by side
template <class S, class Lhs, class Get>
Batch<S> product_each(const Lhs& a, std::size_t n, Get&& x) {
  Batch<S> y(n);
  if (n == 1) {
    y[0] = a * x(0);
    return y;
  }
  Eigen::Index cols = 0;
  for (std::size_t b = 0; b < n; ++b) cols += x(b).cols();
  Mat<S> all(x(0).rows(), cols);
  Eigen::Index c = 0;
  for (std::size_t b = 0; b < n; ++b) {
    all.middleCols(c, x(b).cols()) = x(b);
    c += x(b).cols();
  }
  const Mat<S> prod = a * all;
  c = 0;
  for (std::size_t b = 0; b < n; ++b) {
    y[b] = prod.middleCols(c, x(b).cols());
    c += x(b).cols();
  }
  return y;
}

// ---- layers (batched; `cache(b)` is sample b's cache, `g[b]` the gradient sample b adds to) -------

template <class S>
void im2col(const Conv& c, const Mat<S>& x, ConvC<S>& cc) {
  const int L = static_cast<int>(x.cols());
  const int lout = (L + 2 * c.pad - c.k) / c.stride + 1;
  cc.lin = L;
  cc.xcol.setZero(c.cin * c.k, lout);
  for (int t = 0; t < lout; ++t)
    for (int j = 0; j < c.k; ++j) {
      const int s = t * c.stride + j - c.pad;
      if (s < 0 || s >= L) continue;
      for (int i = 0; i < c.cin; ++i) cc.xcol(i * c.k + j, t) = x(i, s);
    }
}

template <class S>
Mat<S> col2im(const Conv& c, const Mat<S>& dcol, int lin) {
  Mat<S> dx = Mat<S>::Zero(c.cin, lin);
  const int lout = static_cast<int>(dcol.cols());
  for (int t = 0; t < lout; ++t)
    for (int j = 0; j < c.k; ++j) {
      const int s = t * c.stride + j - c.pad;
      if (s < 0 || s >= lin) continue;
      for (int i = 0; i < c.cin; ++i) dx(i, s) += dcol(i * c.k + j, t);
    }
  return dx;
}

template <class S, class Cache>
Batch<S> conv_fwd_each(const Conv& c, const S* p, const Batch<S>& x, Cache&& cache) {
  for (std::size_t b = 0; b < x.size(); ++b) im2col(c, x[b], cache(b));
  Batch<S> y = product_each<S>(CRowMap<S>(p + c.w, c.cout, c.cin * c.k), x.size(), [&](std::size_t b) -> const Mat<S>& { return cache(b).xcol; });
  for (Mat<S>& yb : y) yb.colwise() += CVecMap<S>(p + c.b, c.cout);
  return y;
}

template <class S, class Cache>
Batch<S> conv_bwd_each(const Conv& c, const S* p, const Batch<S>& dy, Cache&& cache, S* const* g, bool need_dx) {
  for (std::size_t b = 0; b < dy.size(); ++b) {
    RowMap<S>(g[b] + c.w, c.cout, c.cin * c.k).noalias() += dy[b] * cache(b).xcol.transpose();
    VecMap<S>(g[b] + c.b, c.cout) += dy[b].rowwise().sum();
  }
  if (!need_dx) return {};
  Batch<S> dx = product_each<S>(CRowMap<S>(p + c.w, c.cout, c.cin * c.k).transpose(), dy.size(), [&](std::size_t b) -> const Mat<S>& { return dy[b]; });
  for (std::size_t b = 0; b < dy.size(); ++b) dx[b] = col2im(c, dx[b], cache(b).lin);
  return dx;
}

// ConvTranspose1d: y(o, s*stride - pad + j) += sum_i W(i, o, j) x(i, s); the cache is the input
template <class S, class Cache>
Batch<S> tconv_fwd_each(const TConv& c, const S* p, const Batch<S>& x, Cache&& cache) {
  Batch<S> z = product_each<S>(CRowMap<S>(p + c.w, c.cin, c.cout * c.k).transpose(), x.size(), [&](std::size_t b) -> const Mat<S>& { return x[b]; });
  Batch<S> y(x.size());
  for (std::size_t b = 0; b < x.size(); ++b) {
    cache(b) = x[b];
    const int L = static_cast<int>(x[b].cols());
    const int lout = (L - 1) * c.stride - 2 * c.pad + c.k;
    y[b].resize(c.cout, lout);
    y[b].colwise() = CVecMap<S>(p + c.b, c.cout);
    for (int s = 0; s < L; ++s)
      for (int j = 0; j < c.k; ++j) {
        const int t = s * c.stride - c.pad + j;
        if (t < 0 || t >= lout) continue;
        for (int o = 0; o < c.cout; ++o) y[b](o, t) += z[b](o * c.k + j, s);
      }
  }
  return y;
}

template <class S, class Cache>
Batch<S> tconv_bwd_each(const TConv& c, const S* p, const Batch<S>& dy, Cache&& cache, S* const* g) {
  Batch<S> dz(dy.size());
  for (std::size_t b = 0; b < dy.size(); ++b) {
    const Mat<S>& x = cache(b);
    const int L = static_cast<int>(x.cols());
    const int lout = static_cast<int>(dy[b].cols());
    dz[b] = Mat<S>::Zero(c.cout * c.k, L);
    for (int s = 0; s < L; ++s)
      for (int j = 0; j < c.k; ++j) {
        const int t = s * c.stride - c.pad + j;
        if (t < 0 || t >= lout) continue;
        for (int o = 0; o < c.cout; ++o) dz[b](o * c.k + j, s) = dy[b](o, t);
      }
    RowMap<S>(g[b] + c.w, c.cin, c.cout * c.k).noalias() += x * dz[b].transpose();
    VecMap<S>(g[b] + c.b, c.cout) += dy[b].rowwise().sum();
  }
  return product_each<S>(CRowMap<S>(p + c.w, c.cin, c.cout * c.k), dy.size(), [&](std::size_t b) -> const Mat<S>& { return dz[b]; });
}

template <class S>
Mat<S> gn_fwd(const Gn& g, const S* p, const Mat<S>& x, GnC<S>& gc) {
  const int C = static_cast<int>(x.rows()), L = static_cast<int>(x.cols()), cpg = C / g.groups;
  const S n = static_cast<S>(cpg * L);
  gc.xhat.resize(C, L);
  gc.rstd.resize(g.groups);
  for (int gi = 0; gi < g.groups; ++gi) {
    const auto blk = x.middleRows(gi * cpg, cpg);
    const S mean = blk.sum() / n;
    const S var = (blk.array() - mean).square().sum() / n;
    const S rstd = S(1) / std::sqrt(var + static_cast<S>(kGroupNormEps));
    gc.rstd(gi) = rstd;
    gc.xhat.middleRows(gi * cpg, cpg) = (blk.array() - mean) * rstd;
  }
  Mat<S> y = CVecMap<S>(p + g.w, C).asDiagonal() * gc.xhat;
  y.colwise() += CVecMap<S>(p + g.b, C);
  return y;
}

template <class S>
Mat<S> gn_bwd(const Gn& g, const S* p, const Mat<S>& dy, const GnC<S>& gc, S* grad) {
  const int C = static_cast<int>(dy.rows()), L = static_cast<int>(dy.cols()), cpg = C / g.groups;
  const S n = static_cast<S>(cpg * L);
  VecMap<S>(grad + g.w, C) += dy.cwiseProduct(gc.xhat).rowwise().sum();
  VecMap<S>(grad + g.b, C) += dy.rowwise().sum();
  const Mat<S> dxhat = CVecMap<S>(p + g.w, C).asDiagonal() * dy;
  Mat<S> dx(C, L);
  for (int gi = 0; gi < g.groups; ++gi) {
    const auto d = dxhat.middleRows(gi * cpg, cpg);
    const auto xh = gc.xhat.middleRows(gi * cpg, cpg);
    const S sd = d.sum();
    const S sdx = d.cwiseProduct(xh).sum();
    dx.middleRows(gi * cpg, cpg) = (gc.rstd(gi) / n) * (n * d.array() - sd - xh.array() * sdx);
  }
  return dx;
}

// Conv1d - GroupNorm - Mish
template <class S, class Cache>
Batch<S> block_fwd_each(const Block& bl, const S* p, const Batch<S>& x, Cache&& cache) {
  Batch<S> y = conv_fwd_each(bl.conv, p, x, [&](std::size_t b) -> ConvC<S>& { return cache(b).conv; });
  for (std::size_t b = 0; b < y.size(); ++b) {
    BlockC<S>& bc = cache(b);
    bc.pre = gn_fwd(bl.gn, p, y[b], bc.gn);
    bc.tn = bc.pre.unaryExpr([](S v) { return std::tanh(softplus(v)); });
    y[b] = bc.pre.binaryExpr(bc.tn, [](S v, S tn) { return v * tn; });  // mish(v), bit for bit
  }
  return y;
}

template <class S, class Cache>
Batch<S> block_bwd_each(const Block& bl, const S* p, const Batch<S>& dy, Cache&& cache, S* const* g, bool need_dx) {
  Batch<S> dconv(dy.size());
  for (std::size_t b = 0; b < dy.size(); ++b) {
    const Mat<S> dpre = dy[b].cwiseProduct(cache(b).pre.binaryExpr(cache(b).tn, [](S v, S tn) { return mish_grad_tn(v, tn); }));
    dconv[b] = gn_bwd(bl.gn, p, dpre, cache(b).gn, g[b]);
  }
  return conv_bwd_each(bl.conv, p, dconv, [&](std::size_t b) -> const ConvC<S>& { return cache(b).conv; }, g, need_dx);
}

// FiLM: [scale, bias] = film(mcond) (2 * C); y = scale * x + bias, per channel
template <class S>
Mat<S> film_fwd(const Lin& film, const S* p, const Mat<S>& x, const Vec<S>& mcond, Vec<S>& scale) {
  const int C = static_cast<int>(x.rows());
  Vec<S> e = CRowMap<S>(p + film.w, film.out, film.in) * mcond;
  e += CVecMap<S>(p + film.b, film.out);
  scale = e.head(C);
  Mat<S> y = scale.asDiagonal() * x;
  y.colwise() += e.tail(C);
  return y;
}

// adds the FiLM parameters' gradient and d/d(mcond) to dmcond; returns d/dx
template <class S>
Mat<S> film_bwd(const Lin& film, const S* p, const Mat<S>& dy, const Mat<S>& x, const Vec<S>& mcond, const Vec<S>& scale,
                Vec<S>& dmcond, S* g) {
  const int C = static_cast<int>(x.rows());
  Vec<S> de(2 * C);
  de.head(C) = dy.cwiseProduct(x).rowwise().sum();
  de.tail(C) = dy.rowwise().sum();
  RowMap<S>(g + film.w, film.out, film.in).noalias() += de * mcond.transpose();
  VecMap<S>(g + film.b, film.out) += de;
  dmcond.noalias() += CRowMap<S>(p + film.w, film.out, film.in).transpose() * de;
  return scale.asDiagonal() * dy;
}

// conditional residual block; mcond(b) is sample b's Mish(cond)
template <class S, class Cond, class Cache>
Batch<S> res_fwd_each(const Res& r, const S* p, const Batch<S>& x, Cond&& mcond, Cache&& cache) {
  const Batch<S> out1 = block_fwd_each(r.b0, p, x, [&](std::size_t b) -> BlockC<S>& { return cache(b).b0; });
  Batch<S> filmed(x.size());
  for (std::size_t b = 0; b < x.size(); ++b) {
    ResC<S>& rc = cache(b);
    rc.out1 = out1[b];
    filmed[b] = film_fwd(r.film, p, rc.out1, mcond(b), rc.scale);
  }
  Batch<S> y = block_fwd_each(r.b1, p, filmed, [&](std::size_t b) -> BlockC<S>& { return cache(b).b1; });
  if (r.has_res) {
    const Batch<S> rx = conv_fwd_each(r.res, p, x, [&](std::size_t b) -> ConvC<S>& { return cache(b).res; });
    for (std::size_t b = 0; b < y.size(); ++b) y[b] += rx[b];
  } else {
    for (std::size_t b = 0; b < y.size(); ++b) y[b] += x[b];
  }
  return y;
}

// dmcond(b): sample b's d/d(Mish(cond)), added to
template <class S, class Cond, class DCond, class Cache>
Batch<S> res_bwd_each(const Res& r, const S* p, const Batch<S>& dy, Cond&& mcond, DCond&& dmcond, Cache&& cache, S* const* g) {
  const Batch<S> dout2 = block_bwd_each(r.b1, p, dy, [&](std::size_t b) -> const BlockC<S>& { return cache(b).b1; }, g, true);
  Batch<S> dout1(dy.size());
  for (std::size_t b = 0; b < dy.size(); ++b) {
    const ResC<S>& rc = cache(b);
    dout1[b] = film_bwd(r.film, p, dout2[b], rc.out1, mcond(b), rc.scale, dmcond(b), g[b]);
  }
  Batch<S> dx = block_bwd_each(r.b0, p, dout1, [&](std::size_t b) -> const BlockC<S>& { return cache(b).b0; }, g, true);
  if (r.has_res) {
    const Batch<S> dr = conv_bwd_each(r.res, p, dy, [&](std::size_t b) -> const ConvC<S>& { return cache(b).res; }, g, true);
    for (std::size_t b = 0; b < dx.size(); ++b) dx[b] += dr[b];
  } else {
    for (std::size_t b = 0; b < dx.size(); ++b) dx[b] += dy[b];
  }
  return dx;
}

// ---- one sample: a batch of one ------------------------------------------------------------------

template <class S>
Mat<S> conv_fwd(const Conv& c, const S* p, const Mat<S>& x, ConvC<S>& cc) {
  return std::move(conv_fwd_each(c, p, Batch<S>{x}, [&](std::size_t) -> ConvC<S>& { return cc; })[0]);
}
template <class S>
Mat<S> conv_bwd(const Conv& c, const S* p, const Mat<S>& dy, const ConvC<S>& cc, S* g, bool need_dx) {
  Batch<S> dx = conv_bwd_each(c, p, Batch<S>{dy}, [&](std::size_t) -> const ConvC<S>& { return cc; }, &g, need_dx);
  return need_dx ? std::move(dx[0]) : Mat<S>();
}
template <class S>
Mat<S> tconv_fwd(const TConv& c, const S* p, const Mat<S>& x, Mat<S>& cache) {
  return std::move(tconv_fwd_each(c, p, Batch<S>{x}, [&](std::size_t) -> Mat<S>& { return cache; })[0]);
}
template <class S>
Mat<S> tconv_bwd(const TConv& c, const S* p, const Mat<S>& dy, const Mat<S>& x, S* g) {
  return std::move(tconv_bwd_each(c, p, Batch<S>{dy}, [&](std::size_t) -> const Mat<S>& { return x; }, &g)[0]);
}
template <class S>
Mat<S> block_fwd(const Block& bl, const S* p, const Mat<S>& x, BlockC<S>& bc) {
  return std::move(block_fwd_each(bl, p, Batch<S>{x}, [&](std::size_t) -> BlockC<S>& { return bc; })[0]);
}
template <class S>
Mat<S> block_bwd(const Block& bl, const S* p, const Mat<S>& dy, const BlockC<S>& bc, S* g, bool need_dx) {
  Batch<S> dx = block_bwd_each(bl, p, Batch<S>{dy}, [&](std::size_t) -> const BlockC<S>& { return bc; }, &g, need_dx);
  return need_dx ? std::move(dx[0]) : Mat<S>();
}
template <class S>
Mat<S> res_fwd(const Res& r, const S* p, const Mat<S>& x, const Vec<S>& mcond, ResC<S>& rc) {
  return std::move(res_fwd_each(r, p, Batch<S>{x}, [&](std::size_t) -> const Vec<S>& { return mcond; }, [&](std::size_t) -> ResC<S>& { return rc; })[0]);
}
template <class S>
Mat<S> res_bwd(const Res& r, const S* p, const Mat<S>& dy, const Vec<S>& mcond, Vec<S>& dmcond, const ResC<S>& rc, S* g) {
  return std::move(res_bwd_each(r, p, Batch<S>{dy}, [&](std::size_t) -> const Vec<S>& { return mcond; },
                                [&](std::size_t) -> Vec<S>& { return dmcond; }, [&](std::size_t) -> const ResC<S>& { return rc; }, &g)[0]);
}

// Linear: y = W x + b
template <class S>
Vec<S> linear_fwd(const Lin& l, const S* p, const Vec<S>& x) {
  return CRowMap<S>(p + l.w, l.out, l.in) * x + CVecMap<S>(p + l.b, l.out);
}

// adds the gradient of W and b; returns d/dx
template <class S>
Vec<S> linear_bwd(const Lin& l, const S* p, const Vec<S>& dy, const Vec<S>& x, S* g) {
  RowMap<S>(g + l.w, l.out, l.in).noalias() += dy * x.transpose();
  VecMap<S>(g + l.b, l.out) += dy;
  return CRowMap<S>(p + l.w, l.out, l.in).transpose() * dy;
}

}  // namespace actionshift::policy::dpnn
