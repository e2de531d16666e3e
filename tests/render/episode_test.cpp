// an episode rendered through the runner's episode function has the runner's record
#include "actionshift/core/error.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/eval/summary.hpp"
#include "actionshift/render/episode.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

namespace actionshift::render {
namespace {

namespace fs = std::filesystem;

eval::JobSpec tiny_job(const std::string& method, std::int64_t episodes) {
  eval::JobRequest q;
  q.task = "pick_cube";
  q.split = "reference_seen";  // two contracts
  q.method.name = method;
  if (method != "oracle" && method != "no_adapt") q.pool = "reference9";
  q.episodes = episodes;
  return eval::resolve_job(q, eval::default_resolver());
}

TEST(RenderEpisode, OutcomeEqualsTheRunnersRecordStepForStep) {
  const eval::JobSpec job = tiny_job("entropy_probes", 3);
  const fs::path dir = fs::temp_directory_path() / ("actionshift_render_episode_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  eval::RunOptions ro;
  ro.out_dir = dir.string();
  ro.threads = 1;
  ro.progress = eval::ProgressMode::off;
  eval::run_job(job, eval::make_episode_fn(job), ro);
  const eval::ResultSet written = eval::load_results(dir.string());
  ASSERT_EQ(written.records.size(), 3u);

  EpisodeRenderOptions o;
  o.width = 64;
  o.height = 48;
  for (const std::int64_t i : {std::int64_t{1}, std::int64_t{2}}) {
    const RenderedEpisode r = render_episode(job, i, o);
    EXPECT_EQ(eval::to_jsonl_line(r.record), eval::to_jsonl_line(written.records[static_cast<std::size_t>(i)])) << "episode " << i;
    // one frame after the reset and one per step taken; the probe flags add up to the record's
    EXPECT_EQ(static_cast<std::int64_t>(r.frames.size()), r.record.steps + 1);
    EXPECT_EQ(std::count(r.probe.begin(), r.probe.end(), true), r.record.probe_steps);
    EXPECT_GT(r.record.probe_steps, 0);
    EXPECT_EQ(std::find(r.success.begin(), r.success.end(), true) != r.success.end(), r.record.success_once);
    for (const auto& f : r.frames) EXPECT_EQ(f.width(), 64);
  }
  fs::remove_all(dir);
}

TEST(RenderEpisode, CleanRunsTheIdentityContractAndIndicesAreChecked) {
  const eval::JobSpec job = tiny_job("no_adapt", 2);
  EpisodeRenderOptions o;
  o.width = 32;
  o.height = 24;
  o.overlay = false;
  o.clean = true;
  const RenderedEpisode clean = render_episode(job, 0, o);
  EXPECT_EQ(clean.record.contract_sha256, Contract::identity().sha256());
  o.clean = false;
  const RenderedEpisode hidden = render_episode(job, 0, o);
  EXPECT_NE(hidden.record.contract_sha256, Contract::identity().sha256());
  // the same episode seed: the same initial state, then different actions take it elsewhere
  EXPECT_EQ(clean.frames.front(), hidden.frames.front());
  EXPECT_FALSE(clean.frames.back() == hidden.frames.back());
  EXPECT_THAT([&] { render_episode(job, 2, o); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("--episode")));
}

}  // namespace
}  // namespace actionshift::render
