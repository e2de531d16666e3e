// Anything chosen by looking at outcomes is chosen on pilot runs that no evaluation uses: the DualABI
// pilot's seeds, and so its episodes' initial states, must be disjoint from every evaluation
// experiment's and from the CLI's default seed.
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

namespace actionshift::eval {
namespace {

const std::filesystem::path kExperiments = std::filesystem::path(ACTIONSHIFT_SOURCE_DIR) / "configs" / "experiments";

bool is_pilot(const std::filesystem::path& p) { return p.stem().string().find("pilot") != std::string::npos; }

TEST(PilotDisjointness, PilotSeedsAndEpisodesAreUsedByNoEvaluation) {
  const Experiment pilot = load_experiment((kExperiments / "dualabi_pilot.yaml").string());
  ASSERT_FALSE(pilot.seeds.empty());
  const std::set<std::uint64_t> pilot_seeds(pilot.seeds.begin(), pilot.seeds.end());
  // the command line's default seed (run, gate0) is an evaluation seed too
  EXPECT_FALSE(pilot_seeds.count(JobRequest{}.seed));
  // every episode seed of the pilot: its splits hold 2 contracts each (reference manifests)
  std::set<std::uint64_t> pilot_episode_seeds;
  for (auto s : pilot.seeds)
    for (std::int64_t c = 0; c < 2; ++c)
      for (std::int64_t e = 0; e < pilot.episodes; ++e) pilot_episode_seeds.insert(episode_seed(s, c, e));
  int evaluations = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kExperiments)) {
    if (entry.path().extension() != ".yaml" || is_pilot(entry.path())) continue;
    const Experiment ex = load_experiment(entry.path().string());
    ++evaluations;
    for (auto s : ex.seeds) {
      EXPECT_FALSE(pilot_seeds.count(s)) << entry.path() << " evaluates on pilot seed " << s;
      // the largest split has 32 evaluation contracts
      for (std::int64_t c = 0; c < 32; ++c)
        for (std::int64_t e = 0; e < std::min<std::int64_t>(ex.episodes, 256); ++e)
          ASSERT_FALSE(pilot_episode_seeds.count(episode_seed(s, c, e))) << entry.path() << " shares a pilot episode";
    }
  }
  EXPECT_GE(evaluations, 4);  // gate1, premise, smoke, tournament, tournament_smoke
}

}  // namespace
}  // namespace actionshift::eval
