// The batched (structure-of-arrays) belief against one PoolBelief per environment.
#include "actionshift/adapt/batched_belief.hpp"
#include "actionshift/adapt/pool_belief.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "synthetic.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <deque>

namespace actionshift::adapt {
namespace {

// N environments with different truths, rotations, episode boundaries and invalid transitions:
// every environment's batched belief matches its own PoolBelief within 1e-12 at every step
void check_against_single(const std::vector<Contract>& pool, int num_envs, int steps) {
  const ResponseModel model = testing::pick_like();
  BatchedPoolBelief batched(pool, model, num_envs);
  std::deque<PoolBelief> single;  // PoolBelief is not movable-assignable into a vector by value cheaply
  std::vector<Decoder> truth;
  Rng rng(5);
  for (int e = 0; e < num_envs; ++e) {
    single.emplace_back(pool, model);
    truth.emplace_back(pool[static_cast<std::size_t>(rng.uniform_int(pool.size()))]);
  }
  BatchedPoolBelief::Batch raw(kActionDim, num_envs);
  BatchedPoolBelief::PoseBatch obs(kPoseDim, num_envs);
  std::vector<Mat3> R(static_cast<std::size_t>(num_envs));
  std::unique_ptr<bool[]> reset(new bool[static_cast<std::size_t>(num_envs)]), invalid(new bool[static_cast<std::size_t>(num_envs)]);
  for (int k = 0; k < steps; ++k) {
    for (int e = 0; e < num_envs; ++e) {
      const auto ue = static_cast<std::size_t>(e);
      R[ue] = Eigen::AngleAxisd(0.3 * k + e, Vec3(1, 2, 3 + e).normalized()).toRotationMatrix();
      raw.col(e) = testing::intent(k + 3 * e);
      reset[ue] = (k + e) % 7 == 0;    // an episode starts
      invalid[ue] = (k + e) % 11 == 5;  // a transition across an episode boundary
      const Action exec = truth[ue].step(raw.col(e), R[ue], reset[ue]);
      Pose6 y = model.expected(exec);
      for (int c = 0; c < kPoseDim; ++c) y[c] += model.sigma[static_cast<std::size_t>(c)] * rng.normal();
      obs.col(e) = y;
      single[ue].update(raw.col(e), y, R[ue], reset[ue], invalid[ue]);
    }
    batched.update(raw, obs, R, std::span<const bool>(reset.get(), static_cast<std::size_t>(num_envs)),
                   std::span<const bool>(invalid.get(), static_cast<std::size_t>(num_envs)));
    std::vector<int> maps(static_cast<std::size_t>(num_envs));
    batched.map_indices(maps);
    for (int e = 0; e < num_envs; ++e) {
      const auto& want = single[static_cast<std::size_t>(e)].log_probs();
      for (int h = 0; h < batched.size(); ++h)
        ASSERT_NEAR(batched.log_probs()(e, h), want[h], 1e-12 * std::max(1.0, std::abs(want[h]))) << "step " << k << " env " << e << " h " << h;
      ASSERT_EQ(batched.map_index(e), single[static_cast<std::size_t>(e)].map_index()) << "step " << k << " env " << e;
      ASSERT_EQ(maps[static_cast<std::size_t>(e)], batched.map_index(e));
      ASSERT_NEAR(batched.entropy(e), single[static_cast<std::size_t>(e)].entropy(), 1e-12);
      const Action a = testing::intent(k);
      const Action want_enc = single[static_cast<std::size_t>(e)].map_encode(a, R[static_cast<std::size_t>(e)]);
      ASSERT_TRUE(batched.map_encode(e, a, R[static_cast<std::size_t>(e)]).isApprox(want_enc, 1e-12));
    }
  }
}

TEST(BatchedPoolBelief, MatchesOnePoolBeliefPerEnvironmentOnReference9) { check_against_single(reference::pool9(), 7, 30); }

TEST(BatchedPoolBelief, MatchesOnePoolBeliefPerEnvironmentOnTheFullPool) {
  check_against_single(data::resolve_manifest("full").contracts(), 3, 12);
}

TEST(BatchedPoolBelief, RejectsBadShapes) {
  EXPECT_THROW(BatchedPoolBelief(reference::pool9(), testing::pick_like(), 0), std::invalid_argument);
  EXPECT_THROW(BatchedPoolBelief({}, testing::pick_like(), 2), std::invalid_argument);
  BatchedPoolBelief b(reference::pool9(), testing::pick_like(), 2);
  EXPECT_THROW(b.update(BatchedPoolBelief::Batch::Zero(kActionDim, 3), BatchedPoolBelief::PoseBatch::Zero(kPoseDim, 2)),
               std::invalid_argument);
  const bool one[1] = {true};
  EXPECT_THROW(b.update(BatchedPoolBelief::Batch::Zero(kActionDim, 2), BatchedPoolBelief::PoseBatch::Zero(kPoseDim, 2), {}, {},
                        std::span<const bool>(one, 1)),
               std::invalid_argument);
  EXPECT_THROW(b.map_index(2), std::invalid_argument);
  EXPECT_NEAR(b.entropy(1), std::log(9.0), 1e-12);
}

}  // namespace
}  // namespace actionshift::adapt
