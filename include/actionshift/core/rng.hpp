#pragma once
/// \file A portable, seeded random number generator. std::mt19937_64's output sequence is fixed
/// by the standard, but std::*_distribution are not; the conversions here are written out so a
/// seed gives the same numbers with every standard library.

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <random>
#include <stdexcept>

namespace actionshift {

/// SplitMix64 finaliser: a bijective 64-bit mixer.
constexpr std::uint64_t splitmix64(std::uint64_t x) noexcept {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// Combines several integers into one well-mixed 64-bit seed (order matters), e.g.
/// `derive_seed({experiment_seed, contract_index, episode_index})`.
constexpr std::uint64_t derive_seed(std::initializer_list<std::uint64_t> parts) noexcept {
  std::uint64_t h = 0x6a09e667f3bcc909ULL;  // sqrt(2) fractional bits
  for (std::uint64_t p : parts) h = splitmix64(h ^ splitmix64(p));
  return h;
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed = 0) : engine_(seed) {}

  std::uint64_t next_u64() { return engine_(); }

  /// Uniform integer in [0, n), unbiased (rejection sampling). Throws if n == 0.
  std::uint64_t uniform_int(std::uint64_t n) {
    if (n == 0) throw std::invalid_argument("Rng::uniform_int: empty range");
    const std::uint64_t limit = UINT64_MAX - (UINT64_MAX % n + 1) % n;  // largest multiple of n, minus 1
    std::uint64_t x;
    do x = engine_();
    while (x > limit);
    return x % n;
  }

  /// Uniform double in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Uniform double in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal (Box–Muller, one value per call; the second is discarded for simplicity).
  double normal() {
    double u1;
    do u1 = uniform();
    while (u1 <= 0.0);
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  double normal(double mean, double std) { return mean + std * normal(); }
  bool coin() { return (engine_() >> 63) != 0; }

  /// Fisher–Yates shuffle of a random-access container.
  template <class C>
  void shuffle(C& c) {
    for (std::size_t i = c.size(); i > 1; --i) {
      const auto j = static_cast<std::size_t>(uniform_int(i));
      std::swap(c[i - 1], c[j]);
    }
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace actionshift
