#include "actionshift/eval/statistics.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace actionshift::eval {

nlohmann::json wilson_json(const WilsonInterval& w) {
  return {{"successes", w.successes}, {"total", w.total}, {"rate", w.rate},
          {"lower", w.lower},         {"upper", w.upper}, {"confidence", w.confidence}};
}


std::uint64_t BoundedRng::below(std::uint64_t n) {
  if (n == 0) throw std::invalid_argument("BoundedRng::below: n must be positive");
  // reject the top (2^64 mod n) values so every residue is equally likely
  const std::uint64_t excess = (std::numeric_limits<std::uint64_t>::max() % n + 1) % n;
  const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() - excess;  // inclusive
  for (;;) {
    const std::uint64_t x = engine_();
    if (x <= limit) return x % n;
  }
}

double linear_quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) throw std::invalid_argument("linear_quantile: empty sample");
  if (!(q >= 0.0 && q <= 1.0)) throw std::invalid_argument("linear_quantile: q must be in [0, 1]");
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const double below = std::floor(pos);
  const auto lo = static_cast<std::size_t>(below);
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  const double t = pos - below;
  const double a = sorted[lo];
  const double b = sorted[hi];
  // numpy's _lerp: a + (b−a)·t, computed from the upper end when t ≥ 0.5 (exact at t = 1)
  const double diff = b - a;
  return t >= 0.5 ? b - diff * (1.0 - t) : a + diff * t;
}

namespace {

void check_bootstrap_args(double confidence, std::size_t samples) {
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("bootstrap: confidence must be in (0, 1)");
  if (samples == 0) throw std::invalid_argument("bootstrap: samples must be positive");
}

// resampled means of `values`, sorted; integer-valued inputs keep exact sums
// the percentile interval of resampled statistics around `estimate`
BootstrapInterval percentile_interval(std::vector<double> stats, double estimate, double confidence, std::size_t pairs,
                                      std::uint64_t seed) {
  std::sort(stats.begin(), stats.end());
  BootstrapInterval out;
  out.estimate = estimate;
  const double alpha = (1.0 - confidence) / 2.0;
  out.lower = linear_quantile(stats, alpha);
  out.upper = linear_quantile(stats, 1.0 - alpha);
  out.confidence = confidence;
  out.samples = stats.size();
  out.pairs = pairs;
  out.seed = seed;
  return out;
}

BootstrapInterval percentile_bootstrap(const std::vector<double>& values, double confidence,
                                       std::size_t samples, std::uint64_t seed) {
  const std::size_t n = values.size();
  BoundedRng rng(seed);
  std::vector<double> means(samples);
  for (std::size_t s = 0; s < samples; ++s) {
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k) sum += values[rng.below(n)];
    means[s] = sum / static_cast<double>(n);
  }
  double total = 0.0;
  for (double v : values) total += v;
  return percentile_interval(std::move(means), total / static_cast<double>(n), confidence, n, seed);
}

}  // namespace

BootstrapInterval bootstrap_interval(const std::vector<double>& values, double confidence,
                                     std::size_t samples, std::uint64_t seed) {
  check_bootstrap_args(confidence, samples);
  if (values.empty()) throw std::invalid_argument("bootstrap_interval: values must not be empty");
  for (double v : values)
    if (!std::isfinite(v)) throw std::invalid_argument("bootstrap_interval: values must be finite");
  return percentile_bootstrap(values, confidence, samples, seed);
}

BootstrapInterval paired_success_difference(const std::vector<bool>& candidate,
                                            const std::vector<bool>& baseline, double confidence,
                                            std::size_t samples, std::uint64_t seed) {
  check_bootstrap_args(confidence, samples);
  if (candidate.size() != baseline.size())
    throw std::invalid_argument("paired inputs must contain the same number of episodes (candidate " +
                                std::to_string(candidate.size()) + ", baseline " +
                                std::to_string(baseline.size()) + ")");
  if (candidate.empty()) throw std::invalid_argument("paired inputs must contain at least one episode");
  std::vector<double> d(candidate.size());
  for (std::size_t k = 0; k < d.size(); ++k)
    d[k] = static_cast<double>(static_cast<int>(candidate[k]) - static_cast<int>(baseline[k]));
  return percentile_bootstrap(d, confidence, samples, seed);
}

BootstrapInterval hierarchical_bootstrap(const ClusteredValues& values, double confidence, std::size_t samples,
                                         std::uint64_t seed) {
  check_bootstrap_args(confidence, samples);
  const auto bad = [](const std::string& what) { throw std::invalid_argument("hierarchical_bootstrap: " + what); };
  if (values.empty()) bad("no backbone");
  // the blocks' means: the innermost level is never resampled within (a block is kept whole)
  std::vector<std::vector<std::vector<double>>> block_means(values.size());
  std::size_t episodes = 0;
  for (std::size_t b = 0; b < values.size(); ++b) {
    if (values[b].empty()) bad("backbone " + std::to_string(b) + " has no seed");
    for (std::size_t s = 0; s < values[b].size(); ++s) {
      if (values[b][s].empty()) bad("backbone " + std::to_string(b) + ", seed " + std::to_string(s) + " has no block");
      std::vector<double> means;
      for (const auto& block : values[b][s]) {
        if (block.empty()) bad("an empty block");
        double sum = 0.0;
        for (double v : block) {
          if (!std::isfinite(v)) bad("values must be finite");
          sum += v;
        }
        means.push_back(sum / static_cast<double>(block.size()));
        episodes += block.size();
      }
      block_means[b].push_back(std::move(means));
    }
  }
  const auto mean_of = [](const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  };
  std::vector<double> backbone_means;
  for (const auto& seeds : block_means) {
    std::vector<double> seed_means;
    for (const auto& blocks : seeds) seed_means.push_back(mean_of(blocks));
    backbone_means.push_back(mean_of(seed_means));
  }
  BoundedRng rng(seed);
  std::vector<double> stats(samples);
  for (std::size_t r = 0; r < samples; ++r) {
    double over_backbones = 0.0;
    for (std::size_t i = 0; i < block_means.size(); ++i) {
      const auto& seeds = block_means[rng.below(block_means.size())];
      double over_seeds = 0.0;
      for (std::size_t j = 0; j < seeds.size(); ++j) {
        const auto& blocks = seeds[rng.below(seeds.size())];
        double over_blocks = 0.0;
        for (std::size_t k = 0; k < blocks.size(); ++k) over_blocks += blocks[rng.below(blocks.size())];
        over_seeds += over_blocks / static_cast<double>(blocks.size());
      }
      over_backbones += over_seeds / static_cast<double>(seeds.size());
    }
    stats[r] = over_backbones / static_cast<double>(block_means.size());
  }
  return percentile_interval(std::move(stats), mean_of(backbone_means), confidence, episodes, seed);
}

TwoProportionSummary two_proportion_summary(std::int64_t successes_a, std::int64_t total_a,
                                            std::int64_t successes_b, std::int64_t total_b, double z) {
  TwoProportionSummary out;
  out.a = wilson_interval(successes_a, total_a, z);
  out.b = wilson_interval(successes_b, total_b, z);
  out.difference = out.a.rate - out.b.rate;
  out.absolute_difference = std::fabs(out.difference);
  // Newcombe (1998) method 10: combine the two Wilson intervals
  const double da_lo = out.a.rate - out.a.lower, da_hi = out.a.upper - out.a.rate;
  const double db_lo = out.b.rate - out.b.lower, db_hi = out.b.upper - out.b.rate;
  out.lower = out.difference - std::sqrt(da_lo * da_lo + db_hi * db_hi);
  out.upper = out.difference + std::sqrt(da_hi * da_hi + db_lo * db_lo);
  out.intervals_overlap = std::max(out.a.lower, out.b.lower) <= std::min(out.a.upper, out.b.upper);
  return out;
}

}  // namespace actionshift::eval
