// Identifier inference: contract field labels, decoding the heads' logits, per-episode network state
#include "actionshift/adapt/identifier.hpp"

#include "actionshift/core/grammar.hpp"
#include "actionshift/core/transforms.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace actionshift::adapt {
namespace {

int argmax(const Eigen::Ref<const Eigen::VectorXf>& v, int start, int n) {
  int best = 0;
  for (int k = 1; k < n; ++k)
    if (v[start + k] > v[start + best]) best = k;
  return best;
}

}  // namespace

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

}  // namespace actionshift::adapt
