#include "actionshift/eval/statistics.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

namespace actionshift::eval {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Appendix A.3: exact doubles from the reference implementation
TEST(Wilson, ReproducesReferenceValuesBitForBit) {
  const auto a = wilson_interval(557, 600);
  EXPECT_EQ(a.lower, 0.9048557485506726);
  EXPECT_EQ(a.upper, 0.9463610609142571);
  const auto b = wilson_interval(600, 600);
  EXPECT_EQ(b.lower, 0.9936382989862994);
  EXPECT_EQ(b.upper, 1.0000000000000002);  // not clamped, as the reference
  const auto c = wilson_interval(0, 600);
  EXPECT_EQ(c.lower, 0.0);
  EXPECT_EQ(c.upper, 0.006361701013700707);
  const auto d = wilson_interval(50, 100);
  EXPECT_NEAR(d.lower, 0.4038315304, 5e-11);
  EXPECT_NEAR(d.upper, 0.5961684696, 5e-11);
  EXPECT_EQ(d.rate, 0.5);
  EXPECT_EQ(d.successes, 50);
  EXPECT_EQ(d.total, 100);
  // the reference implementation's summary example (docs/reference.md, Statistics): two episodes, one success
  const auto e = wilson_interval(1, 2);
  EXPECT_NEAR(e.lower, 0.0945312057, 5e-11);
  EXPECT_NEAR(e.upper, 0.9054687943, 5e-11);
}

TEST(Wilson, ZConstantIsTheReferenceDouble) {
  // the literal is one ulp above; with it 0/600 would not give the reference's exact 0.0
  EXPECT_EQ(kZ95, 1.9599639845400536);
  EXPECT_NE(wilson_interval(0, 600, 1.959963984540054).lower, 0.0);
}

TEST(Wilson, RejectsBadCounts) {
  EXPECT_THAT([] { wilson_interval(0, 0); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("at least one trial is required")));
  EXPECT_THAT([] { wilson_interval(5, 4); }, ThrowsMessage<std::invalid_argument>(HasSubstr("successes must be in [0, total]")));
  EXPECT_THAT([] { wilson_interval(-1, 4); }, ThrowsMessage<std::invalid_argument>(HasSubstr("successes must be in")));
}

TEST(BoundedRng, IsTheStandardMt19937_64Sequence) {
  // the standard fixes mt19937_64's 10000th output for the default seed
  BoundedRng rng(std::mt19937_64::default_seed);
  std::uint64_t x = 0;
  for (int i = 0; i < 10000; ++i) x = rng.next_u64();
  EXPECT_EQ(x, 9981545732273789042ull);
}

TEST(BoundedRng, StaysInRangeAndIsRoughlyUniform) {
  BoundedRng rng(42);
  std::vector<int> counts(7, 0);
  for (int i = 0; i < 70000; ++i) {
    const auto v = rng.below(7);
    ASSERT_LT(v, 7u);
    ++counts[v];
  }
  for (int c : counts) EXPECT_NEAR(c, 10000, 500);
  EXPECT_EQ(BoundedRng(9).below(1), 0u);
  EXPECT_THROW(BoundedRng(1).below(0), std::invalid_argument);
}

TEST(BoundedRng, PinnedSequenceForSeed) {
  // golden values: a change of engine or reduction changes every bootstrap interval
  BoundedRng rng(20260718);
  std::vector<std::uint64_t> got;
  for (int i = 0; i < 5; ++i) got.push_back(rng.below(600));
  BoundedRng again(20260718);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(again.below(600), got[static_cast<std::size_t>(i)]);
  std::mt19937_64 raw(20260718);
  EXPECT_EQ(got[0], raw() % 600);  // first draw is never rejected for n = 600 (probability 2^-55)
}

TEST(LinearQuantile, MatchesNumpyLinear) {
  const std::vector<double> v = {1.0, 2.0, 3.0, 4.0};
  EXPECT_DOUBLE_EQ(linear_quantile(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(linear_quantile(v, 1.0), 4.0);
  EXPECT_DOUBLE_EQ(linear_quantile(v, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(linear_quantile(v, 0.025), 1.075);   // numpy.quantile([1,2,3,4], 0.025)
  EXPECT_DOUBLE_EQ(linear_quantile(v, 0.975), 3.925);
  EXPECT_DOUBLE_EQ(linear_quantile({7.0}, 0.3), 7.0);
  EXPECT_THROW(linear_quantile({}, 0.5), std::invalid_argument);
}

TEST(Bootstrap, ContainsTheMeanAndIsReproducible) {
  const std::vector<double> v = {1, 2, 3, 4};
  const auto a = bootstrap_interval(v, 0.95, 2000, 7);
  EXPECT_DOUBLE_EQ(a.estimate, 2.5);
  EXPECT_LE(a.lower, a.estimate);
  EXPECT_GE(a.upper, a.estimate);
  // reference A.3 gives (2.5, 1.5, 3.5) with torch's RNG; ours differs only by Monte Carlo noise
  EXPECT_NEAR(a.lower, 1.5, 0.26);
  EXPECT_NEAR(a.upper, 3.5, 0.26);
  EXPECT_EQ(a, bootstrap_interval(v, 0.95, 2000, 7));
  EXPECT_NE(a.lower + a.upper, bootstrap_interval({1, 2, 3, 4, 5, 6, 7, 8, 9}, 0.95, 2000, 8).lower);
  EXPECT_THROW(bootstrap_interval({}, 0.95), std::invalid_argument);
  EXPECT_THROW(bootstrap_interval({1.0, std::nan("")}, 0.95), std::invalid_argument);
  EXPECT_THROW(bootstrap_interval({1.0}, 1.0), std::invalid_argument);
}

TEST(PairedDifference, FivePairExampleHasEstimateFourTenths) {
  const std::vector<bool> cand = {true, true, false, true, true};
  const std::vector<bool> base = {false, true, false, false, true};
  const auto d = paired_success_difference(cand, base, 0.95, 2000, 3);
  EXPECT_DOUBLE_EQ(d.estimate, 0.4);
  EXPECT_EQ(d.pairs, 5u);
  EXPECT_EQ(d.samples, 2000u);
  // differences are {1,0,0,1,0}: resampled means lie on a 0.2 grid in [0, 1]
  EXPECT_GE(d.lower, 0.0);
  EXPECT_LE(d.upper, 1.0);
  EXPECT_LE(d.lower, 0.4);
  EXPECT_GE(d.upper, 0.4);
  EXPECT_EQ(d, paired_success_difference(cand, base, 0.95, 2000, 3));
}

TEST(PairedDifference, SixHundredPairsMatchReferenceWithinMonteCarloError) {
  std::vector<bool> cand, base;
  for (int k = 0; k < 600; ++k) {
    cand.push_back(k % 3 != 0);
    base.push_back(k % 5 == 0);
  }
  const auto d = paired_success_difference(cand, base);
  EXPECT_EQ(d.estimate, 0.4666666666666667);
  EXPECT_EQ(d.samples, 10000u);
  EXPECT_EQ(d.seed, 20260718u);
  // reference (torch RNG): [0.4166666666666667, 0.5166666666666667]
  EXPECT_NEAR(d.lower, 0.4166666666666667, 0.01);
  EXPECT_NEAR(d.upper, 0.5166666666666667, 0.01);
}

TEST(PairedDifference, IntervalShrinksWithSampleSize) {
  auto width = [](int n) {
    std::vector<bool> c, b;
    for (int k = 0; k < n; ++k) {
      c.push_back(k % 2 == 0);
      b.push_back(k % 4 == 0);
    }
    const auto d = paired_success_difference(c, b, 0.95, 4000, 11);
    return d.upper - d.lower;
  };
  const double w40 = width(40), w400 = width(400), w4000 = width(4000);
  EXPECT_GT(w40, w400);
  EXPECT_GT(w400, w4000);
  EXPECT_NEAR(w40 / w400, std::sqrt(10.0), 0.8);
}

TEST(PairedDifference, RejectsUnequalLengths) {
  EXPECT_THAT([] { paired_success_difference({true, false}, {true}); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("paired inputs must contain the same number of episodes")));
  EXPECT_THROW(paired_success_difference({}, {}), std::invalid_argument);
}

TEST(TwoProportion, NewcombeIntervalAndOverlap) {
  const auto s = two_proportion_summary(75, 100, 73, 100);
  EXPECT_NEAR(s.difference, 0.02, 1e-15);
  EXPECT_NEAR(s.absolute_difference, 0.02, 1e-15);
  EXPECT_TRUE(s.intervals_overlap);
  EXPECT_LT(s.lower, 0.0);
  EXPECT_GT(s.upper, 0.02);
  // Newcombe (1998) Table II example 1: 56/70 vs 48/80 → [0.0524, 0.3339]
  const auto n = two_proportion_summary(56, 70, 48, 80);
  EXPECT_NEAR(n.lower, 0.0524, 5e-5);
  EXPECT_NEAR(n.upper, 0.3339, 5e-5);
  const auto far = two_proportion_summary(90, 100, 50, 100);
  EXPECT_FALSE(far.intervals_overlap);
  EXPECT_GT(far.lower, 0.0);
}


// a backbone of `seeds` seeds x `blocks` blocks of `per_block` episodes, each block's episodes equal
// (success shared by the block's initial state) and the blocks alternating 1, 0 from `first`
std::vector<std::vector<std::vector<double>>> correlated_backbone(int seeds, int blocks, int per_block, double offset) {
  std::vector<std::vector<std::vector<double>>> out(static_cast<std::size_t>(seeds));
  for (int s = 0; s < seeds; ++s)
    for (int b = 0; b < blocks; ++b)
      out[static_cast<std::size_t>(s)].push_back(std::vector<double>(static_cast<std::size_t>(per_block), ((b + s) % 2) + offset));
  return out;
}

TEST(HierarchicalBootstrap, EstimateWeighsBackbonesSeedsAndBlocksEqually) {
  // backbone 0: one seed, blocks {1,1} and {0}: block means 1 and 0 -> 0.5; backbone 1: all 0.25
  const ClusteredValues v = {{{{1.0, 1.0}, {0.0}}}, {{{0.25}}, {{0.25, 0.25}}}};
  const auto r = hierarchical_bootstrap(v, 0.95, 2000, 7);
  EXPECT_DOUBLE_EQ(r.estimate, (0.5 + 0.25) / 2.0);
  EXPECT_EQ(r.pairs, 6u);
  EXPECT_LE(r.lower, r.estimate);
  EXPECT_GE(r.upper, r.estimate);
  EXPECT_EQ(hierarchical_bootstrap(v, 0.95, 2000, 7), r);  // deterministic
  EXPECT_NE(hierarchical_bootstrap(v, 0.95, 2000, 8), r);
}

TEST(HierarchicalBootstrap, ConstantValuesGiveAPointInterval) {
  const ClusteredValues v = {{{{0.3, 0.3}, {0.3}}, {{0.3}}}};
  const auto r = hierarchical_bootstrap(v, 0.95, 500, 1);
  EXPECT_DOUBLE_EQ(r.lower, 0.3);
  EXPECT_DOUBLE_EQ(r.upper, 0.3);
}

// Episodes of a block are one unit: an episode bootstrap that treats 9 copies of each block as 9
// independent episodes is 3 times too narrow; the cluster bootstrap is not fooled by the copies
TEST(HierarchicalBootstrap, ABlocksEpisodesCountOnceNotPerEpisode) {
  const auto one = correlated_backbone(3, 40, 1, 0.0), nine = correlated_backbone(3, 40, 9, 0.0);
  const auto w = [](const BootstrapInterval& i) { return i.upper - i.lower; };
  const double cluster1 = w(hierarchical_bootstrap({one})), cluster9 = w(hierarchical_bootstrap({nine}));
  EXPECT_NEAR(cluster9, cluster1, 0.02);
  std::vector<double> flat;
  for (const auto& seed : nine)
    for (const auto& block : seed) flat.insert(flat.end(), block.begin(), block.end());
  const double naive = w(bootstrap_interval(flat));
  EXPECT_LT(naive * 2.0, cluster9);  // the naive interval is about a third as wide
}

// Backbones that disagree: each one's own interval excludes 0, the pooled one (backbone a random
// effect) includes it; with backbones that agree the pooled interval excludes 0 as each does
TEST(HierarchicalBootstrap, BackboneVariationWidensThePooledInterval) {
  const auto up = correlated_backbone(3, 40, 2, 0.6), down = correlated_backbone(3, 40, 2, -1.4);
  const auto r_up = hierarchical_bootstrap({up}), r_down = hierarchical_bootstrap({down});
  EXPECT_GT(r_up.lower, 0.0);
  EXPECT_LT(r_down.upper, 0.0);
  const auto pooled = hierarchical_bootstrap({up, down, up});
  EXPECT_LT(pooled.lower, 0.0);
  EXPECT_GT(pooled.upper, 0.0);
  const auto agree = hierarchical_bootstrap({up, correlated_backbone(3, 40, 2, 0.55), up});
  EXPECT_GT(agree.lower, 0.0);
}

TEST(HierarchicalBootstrap, EmptyLevelsAndNonFiniteValuesAreRefused) {
  EXPECT_THAT([] { hierarchical_bootstrap({}); }, ThrowsMessage<std::invalid_argument>(HasSubstr("no backbone")));
  EXPECT_THAT([] { hierarchical_bootstrap({{}}); }, ThrowsMessage<std::invalid_argument>(HasSubstr("has no seed")));
  EXPECT_THAT([] { hierarchical_bootstrap({{{}}}); }, ThrowsMessage<std::invalid_argument>(HasSubstr("has no block")));
  EXPECT_THAT([] { hierarchical_bootstrap({{{{}}}}); }, ThrowsMessage<std::invalid_argument>(HasSubstr("empty block")));
  EXPECT_THAT([] { hierarchical_bootstrap({{{{std::nan("")}}}}); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("finite")));
}

}  // namespace
}  // namespace actionshift::eval
