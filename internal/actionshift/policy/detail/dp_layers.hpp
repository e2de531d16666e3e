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
#include <cstdint>

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
template <class S>
S mish_grad(S x) {
  const S tn = std::tanh(softplus(x));
  const S sig = S(1) / (S(1) + std::exp(-x));
  return tn + x * (S(1) - tn * tn) * sig;
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
};
template <class S>
struct ResC {
  BlockC<S> b0, b1;
  Mat<S> out1;
  Vec<S> scale;
  ConvC<S> res;
};

// ---- layers ------------------------------------------------------------------------------------

template <class S>
Mat<S> conv_fwd(const Conv& c, const S* p, const Mat<S>& x, ConvC<S>& cc) {
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
  Mat<S> y = CRowMap<S>(p + c.w, c.cout, c.cin * c.k) * cc.xcol;
  y.colwise() += CVecMap<S>(p + c.b, c.cout);
  return y;
}

template <class S>
Mat<S> conv_bwd(const Conv& c, const S* p, const Mat<S>& dy, const ConvC<S>& cc, S* g, bool need_dx) {
  RowMap<S>(g + c.w, c.cout, c.cin * c.k).noalias() += dy * cc.xcol.transpose();
  VecMap<S>(g + c.b, c.cout) += dy.rowwise().sum();
  if (!need_dx) return {};
  const Mat<S> dcol = CRowMap<S>(p + c.w, c.cout, c.cin * c.k).transpose() * dy;
  Mat<S> dx = Mat<S>::Zero(c.cin, cc.lin);
  const int lout = static_cast<int>(dy.cols());
  for (int t = 0; t < lout; ++t)
    for (int j = 0; j < c.k; ++j) {
      const int s = t * c.stride + j - c.pad;
      if (s < 0 || s >= cc.lin) continue;
      for (int i = 0; i < c.cin; ++i) dx(i, s) += dcol(i * c.k + j, t);
    }
  return dx;
}

// ConvTranspose1d: y(o, s*stride - pad + j) += sum_i W(i, o, j) x(i, s)
template <class S>
Mat<S> tconv_fwd(const TConv& c, const S* p, const Mat<S>& x, Mat<S>& cache) {
  cache = x;
  const int L = static_cast<int>(x.cols());
  const int lout = (L - 1) * c.stride - 2 * c.pad + c.k;
  const Mat<S> z = CRowMap<S>(p + c.w, c.cin, c.cout * c.k).transpose() * x;  // (cout*k) x L
  Mat<S> y(c.cout, lout);
  y.colwise() = CVecMap<S>(p + c.b, c.cout);
  for (int s = 0; s < L; ++s)
    for (int j = 0; j < c.k; ++j) {
      const int t = s * c.stride - c.pad + j;
      if (t < 0 || t >= lout) continue;
      for (int o = 0; o < c.cout; ++o) y(o, t) += z(o * c.k + j, s);
    }
  return y;
}

template <class S>
Mat<S> tconv_bwd(const TConv& c, const S* p, const Mat<S>& dy, const Mat<S>& x, S* g) {
  const int L = static_cast<int>(x.cols());
  const int lout = static_cast<int>(dy.cols());
  Mat<S> dz = Mat<S>::Zero(c.cout * c.k, L);
  for (int s = 0; s < L; ++s)
    for (int j = 0; j < c.k; ++j) {
      const int t = s * c.stride - c.pad + j;
      if (t < 0 || t >= lout) continue;
      for (int o = 0; o < c.cout; ++o) dz(o * c.k + j, s) = dy(o, t);
    }
  RowMap<S>(g + c.w, c.cin, c.cout * c.k).noalias() += x * dz.transpose();
  VecMap<S>(g + c.b, c.cout) += dy.rowwise().sum();
  return CRowMap<S>(p + c.w, c.cin, c.cout * c.k) * dz;
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

template <class S>
Mat<S> block_fwd(const Block& b, const S* p, const Mat<S>& x, BlockC<S>& bc) {
  bc.pre = gn_fwd(b.gn, p, conv_fwd(b.conv, p, x, bc.conv), bc.gn);
  return mish_of(bc.pre);
}

template <class S>
Mat<S> block_bwd(const Block& b, const S* p, const Mat<S>& dy, const BlockC<S>& bc, S* g, bool need_dx) {
  const Mat<S> dpre = dy.cwiseProduct(mish_grad_of(bc.pre));
  return conv_bwd(b.conv, p, gn_bwd(b.gn, p, dpre, bc.gn, g), bc.conv, g, need_dx);
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

template <class S>
Mat<S> res_fwd(const Res& r, const S* p, const Mat<S>& x, const Vec<S>& mcond, ResC<S>& rc) {
  rc.out1 = block_fwd(r.b0, p, x, rc.b0);
  Mat<S> y = block_fwd(r.b1, p, film_fwd(r.film, p, rc.out1, mcond, rc.scale), rc.b1);
  if (r.has_res)
    y += conv_fwd(r.res, p, x, rc.res);
  else
    y += x;
  return y;
}

template <class S>
Mat<S> res_bwd(const Res& r, const S* p, const Mat<S>& dy, const Vec<S>& mcond, Vec<S>& dmcond, const ResC<S>& rc, S* g) {
  const Mat<S> dout2 = block_bwd(r.b1, p, dy, rc.b1, g, true);
  const Mat<S> dout1 = film_bwd(r.film, p, dout2, rc.out1, mcond, rc.scale, dmcond, g);
  Mat<S> dx = block_bwd(r.b0, p, dout1, rc.b0, g, true);
  if (r.has_res)
    dx += conv_bwd(r.res, p, dy, rc.res, g, true);
  else
    dx += dy;
  return dx;
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
