// DAgger trainer: seeded and deterministic, independent of the collection thread count, learns
#include "actionshift/policy/train.hpp"

#include <gtest/gtest.h>

using namespace actionshift;

namespace {

policy::TrainBcOptions tiny(unsigned threads) {
  policy::TrainBcOptions o;
  o.task = sim::TaskId::kPushCube;
  o.hidden = {32, 32};
  o.iterations = 2;
  o.episodes_per_iteration = 4;
  o.steps_per_iteration = 60;
  o.batch_size = 64;
  o.threads = threads;
  return o;
}

TEST(TrainBc, SameSeedSameBytesWhateverTheThreads) {
  const auto a = policy::train_bc(tiny(1));
  const auto b = policy::train_bc(tiny(2));
  EXPECT_EQ(policy::serialize_mlp(a.weights), policy::serialize_mlp(b.weights));
  auto o = tiny(2);
  o.seed = 99;
  EXPECT_NE(policy::serialize_mlp(policy::train_bc(o).weights), policy::serialize_mlp(a.weights));
}

TEST(TrainBc, AggregatesDataAndReducesTheLoss) {
  auto o = tiny(0);
  o.steps_per_iteration = 150;
  std::vector<policy::TrainIteration> its;
  const auto r = policy::train_bc(o, [&its](const policy::TrainIteration& it) { its.push_back(it); });
  ASSERT_EQ(its.size(), 2u);
  EXPECT_EQ(its[0].beta, 1.0);
  EXPECT_EQ(its[0].samples, 4 * 50);
  EXPECT_EQ(its[1].samples, 8 * 50);
  EXPECT_EQ(its[0].successes, 4);  // iteration 0 is the expert
  // the loss at the end is well below the loss of predicting zeros (mean square of the labels)
  EXPECT_LT(its[1].loss, 0.2);
  EXPECT_EQ(r.weights.layers, (std::vector<int>{35, 32, 32, 7}));
}

TEST(TrainBc, RejectsNonPositiveSizes) {
  auto o = tiny(1);
  o.iterations = 0;
  EXPECT_THROW(policy::train_bc(o), std::invalid_argument);
}

}  // namespace
