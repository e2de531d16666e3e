// Training of the learned identifiers: seeded and deterministic, held-out verdicts, smoke-size
#include "actionshift/eval/identifier_train.hpp"

#include "actionshift/core/error.hpp"

#include <gtest/gtest.h>

namespace actionshift::eval {
namespace {

TrainIdentifierOptions smoke(adapt::IdentifierKind kind, std::uint64_t seed) {
  TrainIdentifierOptions o;
  o.kind = kind;
  o.seed = seed;
  o.max_contracts = 3;
  o.episodes_per_contract = 1;
  o.heldout_episodes = 1;
  o.steps = 16;
  o.train_steps = 30;
  o.batch = 16;
  o.threads = 2;
  return o;
}

// `train identifier` reproduces a model from its seed: the same options give the same bytes
// (whatever the thread count), another seed other bytes; the verdicts cover every horizon <= steps.
TEST(IdentifierTrain, SameSeedSameBytesAcrossThreadCounts) {
  for (auto kind : {adapt::IdentifierKind::kOsi, adapt::IdentifierKind::kProbeOsi, adapt::IdentifierKind::kRecurrentOsi}) {
    auto o = smoke(kind, 11);
    const auto a = train_identifier(o);
    o.threads = 1;
    const auto b = train_identifier(o);
    EXPECT_EQ(adapt::serialize_identifier(a.weights), adapt::serialize_identifier(b.weights)) << adapt::identifier_kind_name(kind);
    const auto c = train_identifier(smoke(kind, 12));
    EXPECT_NE(adapt::serialize_identifier(a.weights), adapt::serialize_identifier(c.weights));
    EXPECT_EQ(a.weights.kind, kind);
    EXPECT_EQ(a.heldout.horizons, (std::vector<int>{5, 10, 15}));
    EXPECT_EQ(a.heldout.contracts, 3);
    for (const auto& row : a.heldout.accuracy)
      for (double v : row) EXPECT_TRUE(v >= 0.0 && v <= 1.0);
    EXPECT_TRUE(std::isfinite(a.final_loss));
    // the held-out verdicts are a pure function of the weights and the data settings
    const auto again = evaluate_identifier(a.weights, o);
    EXPECT_EQ(again.to_json(), a.heldout.to_json());
  }
}

// Training fits: after more steps the training loss is well below the loss of uniform heads
// (sum over the 19 groups of log(size) = 6 ln 6 + 6 ln 2 + 6 ln 7 + 3 ln 2 + ln 4 = 30.7).
TEST(IdentifierTrain, LossFallsBelowTheUniformHeads) {
  auto o = smoke(adapt::IdentifierKind::kOsi, 5);
  o.train_steps = 400;
  const auto r = train_identifier(o);
  EXPECT_LT(r.final_loss, 0.6 * 30.7);
}

TEST(IdentifierTrain, BadOptionsAreRejected) {
  auto o = smoke(adapt::IdentifierKind::kOsi, 1);
  o.excitation = "loud";
  EXPECT_THROW(train_identifier(o), InputError);
  o = smoke(adapt::IdentifierKind::kOsi, 1);
  o.batch = 0;
  EXPECT_THROW(train_identifier(o), std::invalid_argument);
  o = smoke(adapt::IdentifierKind::kOsi, 1);
  o.task = "juggle";
  EXPECT_THROW(train_identifier(o), InputError);
}

}  // namespace
}  // namespace actionshift::eval
