#pragma once
// A probing rule of your own, as an ActionShift plug-in (docs/methods.md): for `budget` steps, send
// the ±amplitude basis pulse whose calibrated, lag-aware previews separate the two likeliest pool
// hypotheses most (in units of the response noise); then act on the MAP hypothesis. The same rule in
// Python is docs/examples/separation_probes.py; both make the same decisions step for step.
#include <actionshift/adapt/plugin.hpp>
#include <actionshift/adapt/pool_belief.hpp>

#include <memory>
#include <string>
#include <vector>

namespace separation {

class SeparationProbes final : public actionshift::adapt::Adapter {
 public:
  explicit SeparationProbes(const actionshift::adapt::PluginInputs& in)  // the pool rung's inputs
      : belief_(*in.pool, *in.model), budget_(in.params.at("budget").get<int>()),
        amplitude_(in.params.at("amplitude").get<double>()) {}
  std::string name() const override { return "separation_probes"; }
  void begin_episode(std::uint64_t) override {
    belief_.reset();
    t_ = 0;
  }
  actionshift::Action encode(const actionshift::Action& canonical, const actionshift::Mat3& R) override {
    probe_ = ++t_ <= budget_;
    if (!probe_) return belief_.map_encode(canonical, R);
    const auto& lp = belief_.log_probs();  // the two likeliest hypotheses, the first index on ties
    int a = 0, b = -1;
    for (int h = 1; h < belief_.size(); ++h)
      if (lp[h] > lp[a]) a = h;
    for (int h = 0; h < belief_.size(); ++h)
      if (h != a && (b < 0 || lp[h] > lp[b])) b = h;
    const auto& m = belief_.model();
    actionshift::Action best = actionshift::Action::Zero();
    double best_sep = -1.0;
    for (int c = 0; c < 6; ++c)
      for (double s : {1.0, -1.0}) {
        actionshift::Action raw = actionshift::Action::Zero();
        raw[c] = s * amplitude_;
        belief_.preview(raw, R, /*lag_aware=*/true, preview_);
        double sep = 0.0;
        for (int k = 0; k < 6; ++k) {
          const auto kk = static_cast<std::size_t>(k);
          const double scale = m.alpha[kk] / m.sigma[kk];  // in units of the response noise
          const double d = preview_[static_cast<std::size_t>(a)][k] * scale - preview_[static_cast<std::size_t>(b)][k] * scale;
          sep += d * d;
        }
        if (sep > best_sep) {
          best = raw;
          best_sep = sep;
        }
      }
    return best;
  }
  void observe(const actionshift::Action& raw, const actionshift::Pose6& response, const actionshift::Mat3& R) override {
    belief_.update(raw, response, R);
  }
  actionshift::adapt::StepInfo last_step() const override { return {probe_, -1.0}; }

 private:
  actionshift::adapt::PoolBelief belief_;
  int budget_, t_{0};
  double amplitude_;
  bool probe_{false};
  std::vector<actionshift::Action> preview_;
};

// The plug-in: name, version, rung, the files that define it, parameters and the factory.
inline actionshift::adapt::MethodPlugin plugin(std::vector<std::string> files = {__FILE__}) {
  actionshift::adapt::MethodPlugin p;
  p.name = "separation_probes";
  p.version = "1";
  p.rung = actionshift::adapt::Rung::pool;
  p.files = std::move(files);
  p.params = {{"budget", 6}, {"amplitude", 0.5}};
  p.factory = [](const actionshift::adapt::PluginInputs& in) { return std::make_unique<SeparationProbes>(in); };
  return p;
}

}  // namespace separation
