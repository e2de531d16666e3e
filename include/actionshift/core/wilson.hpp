#pragma once
/// \file The Wilson score interval of a binomial proportion (docs/reference.md, *Statistics*), shared by Gate 0 (policy
/// layer) and the evaluation statistics (eval layer).

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace actionshift {

/// z for a two-sided 95 % interval exactly as the reference computes it:
/// Python's `statistics.NormalDist().inv_cdf(0.975)` = 1.9599639845400536.
/// \note The issue writes z = 1.959963984540054 (the quantile to 16 digits); that literal parses to
/// the double one ulp above this one, and with it 0/600 gives a lower bound of 4.3e-19 instead of
/// the reference's 0.0 (Appendix A.3). The reference's double reproduces every A.3 value bit for bit.
inline constexpr double kZ95 = 1.9599639845400536;

/// A Wilson score interval for a binomial proportion.
struct WilsonInterval {
  std::int64_t successes{0};  ///< number of successes s
  std::int64_t total{0};      ///< number of trials n (> 0)
  double rate{0.0};           ///< s / n
  double lower{0.0};          ///< centre − half-width (not clamped, as the reference)
  double upper{0.0};          ///< centre + half-width (not clamped: 600/600 gives 1.0000000000000002)
  double confidence{0.95};    ///< nominal coverage
  bool operator==(const WilsonInterval&) const = default;
};

/// Wilson score interval with the reference's formula and no clamping:
/// p = s/n, d = 1 + z²/n, centre = (p + z²/(2n))/d, half = z·sqrt(p(1−p)/n + z²/(4n²))/d.
/// `z` defaults to kZ95; `confidence` is recorded only.
/// Throws std::invalid_argument if total ≤ 0 ("at least one trial is required") or successes ∉ [0, total].
inline WilsonInterval wilson_interval(std::int64_t successes, std::int64_t total, double z = kZ95,
                                      double confidence = 0.95) {
  if (total <= 0)
    throw std::invalid_argument("wilson_interval: at least one trial is required (got total " + std::to_string(total) + ")");
  if (successes < 0 || successes > total)
    throw std::invalid_argument("wilson_interval: successes must be in [0, total] (got " + std::to_string(successes) +
                                " of " + std::to_string(total) + ")");
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("wilson_interval: confidence must be in (0, 1)");
  // same operation order as the reference's Python, so results agree to the last bit
  const double n = static_cast<double>(total);
  const double p = static_cast<double>(successes) / n;
  const double z2 = z * z;
  const double denominator = 1.0 + z2 / n;
  const double centre = (p + z2 / (2.0 * n)) / denominator;
  const double half = z * std::sqrt(p * (1.0 - p) / n + z2 / (4.0 * n * n)) / denominator;
  return {successes, total, p, centre - half, centre + half, confidence};
}

}  // namespace actionshift
