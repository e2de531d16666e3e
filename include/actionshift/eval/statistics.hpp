#pragma once
/// \file Statistics for evaluation results: Wilson score intervals, percentile bootstrap, paired
/// success differences and a two-proportion summary (docs/reference.md, *Statistics*).

#include "actionshift/core/wilson.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

namespace actionshift::eval {

using actionshift::kZ95;
/// Default number of bootstrap resamples (docs/reference.md, *Gates*).
inline constexpr std::size_t kBootstrapSamples = 10000;
/// Default bootstrap seed (the reference's experimental seed, §7.6).
inline constexpr std::uint64_t kBootstrapSeed = 20260718;

/// Wilson score interval (core/wilson.hpp).
using actionshift::WilsonInterval;
using actionshift::wilson_interval;

/// {"successes","total","rate","lower","upper","confidence"}: how every summary and verdict file writes an interval.
nlohmann::json wilson_json(const WilsonInterval& w);

/// A percentile bootstrap interval of a mean.
struct BootstrapInterval {
  double estimate{0.0};        ///< mean of the original sample
  double lower{0.0};           ///< quantile (1−confidence)/2 of the resampled means
  double upper{0.0};           ///< quantile 1−(1−confidence)/2 of the resampled means
  double confidence{0.95};     ///< nominal coverage
  std::size_t samples{0};      ///< number of resamples
  std::size_t pairs{0};        ///< sample size (pairs for a paired difference)
  std::uint64_t seed{0};       ///< RNG seed
  bool operator==(const BootstrapInterval&) const = default;
};

/// Uniform integers from std::mt19937_64 (whose output sequence the C++ standard fixes), reduced to
/// [0, n) by rejection: draws ≥ 2⁶⁴ − (2⁶⁴ mod n) are discarded, then x mod n. The sequence is the
/// same on every platform and standard library.
/// \note `std::uniform_int_distribution` is implementation-defined and is deliberately not used.
class BoundedRng {
 public:
  explicit BoundedRng(std::uint64_t seed) : engine_(seed) {}
  /// Raw engine output.
  std::uint64_t next_u64() { return engine_(); }
  /// Uniform in [0, n). Throws std::invalid_argument if n == 0.
  std::uint64_t below(std::uint64_t n);

 private:
  std::mt19937_64 engine_;
};

/// Quantile with linear interpolation between order statistics (numpy's default "linear" method,
/// position q·(n−1) on the sorted sample). `sorted` must be sorted ascending and non-empty; q ∈ [0,1].
double linear_quantile(const std::vector<double>& sorted, double q);

/// Percentile bootstrap of the mean of `values`: `samples` resamples of size n drawn with
/// replacement (indices from BoundedRng(seed)), the resampled means, then linear quantiles.
/// Throws std::invalid_argument for an empty or non-finite sample, samples == 0, confidence ∉ (0,1).
BootstrapInterval bootstrap_interval(const std::vector<double>& values, double confidence = 0.95,
                                     std::size_t samples = kBootstrapSamples,
                                     std::uint64_t seed = kBootstrapSeed);

/// Paired bootstrap of the success difference candidate − baseline: pair k is
/// (candidate[k], baseline[k]); pairs are resampled intact. Estimate = mean difference.
/// Throws std::invalid_argument "paired inputs must contain the same number of episodes" on a length
/// mismatch, and for empty inputs.
BootstrapInterval paired_success_difference(const std::vector<bool>& candidate,
                                            const std::vector<bool>& baseline,
                                            double confidence = 0.95,
                                            std::size_t samples = kBootstrapSamples,
                                            std::uint64_t seed = kBootstrapSeed);

/// Values grouped by the levels that make them dependent, outermost first: backbone → seed → block →
/// episodes (a block is the episodes that share an initial state: one per contract of the split).
using ClusteredValues = std::vector<std::vector<std::vector<std::vector<double>>>>;

/// Hierarchical percentile bootstrap of a mean over clustered values (e.g. paired differences
/// candidate − baseline). Each resample draws backbones with replacement, within each drawn backbone
/// its seeds with replacement, within each drawn seed its blocks with replacement, and keeps a drawn
/// block's episodes whole; its statistic is the mean over the drawn backbones of the mean over their
/// drawn seeds of the mean over their drawn blocks of the block's mean. `estimate` is that statistic
/// on the data (every backbone, seed and block weighted equally). Resampling every level (not only
/// the outermost) counts the variation at each level, so with few backbones the interval errs wide,
/// not narrow; with one backbone it is the cluster bootstrap over (seed, block). `pairs` is the
/// number of episodes. Throws std::invalid_argument for an empty level, a non-finite value,
/// samples == 0 or confidence ∉ (0,1).
BootstrapInterval hierarchical_bootstrap(const ClusteredValues& values, double confidence = 0.95,
                                         std::size_t samples = kBootstrapSamples,
                                         std::uint64_t seed = kBootstrapSeed);

/// Two independent proportions side by side (unpaired): both Wilson intervals, the difference
/// a − b with Newcombe's hybrid score interval (method 10), and whether the Wilson intervals overlap.
struct TwoProportionSummary {
  WilsonInterval a;            ///< first group
  WilsonInterval b;            ///< second group
  double difference{0.0};      ///< a.rate − b.rate
  double lower{0.0};           ///< Newcombe lower bound of the difference
  double upper{0.0};           ///< Newcombe upper bound of the difference
  double absolute_difference{0.0};  ///< |a.rate − b.rate|
  bool intervals_overlap{false};    ///< max(lowers) ≤ min(uppers)
};

/// Summarise two proportions. Throws as wilson_interval does.
TwoProportionSummary two_proportion_summary(std::int64_t successes_a, std::int64_t total_a,
                                            std::int64_t successes_b, std::int64_t total_b,
                                            double z = kZ95);

}  // namespace actionshift::eval
