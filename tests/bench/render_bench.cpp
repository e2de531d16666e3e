// Google Benchmark for the render layer: one 320x240 frame of PickCube, and a whole 50-step episode
// rendered at 320x240 (runner episode, 51 frames with overlay, GIF encoding). One llvmpipe thread
// (LP_NUM_THREADS=0: llvmpipe rasterises in the calling thread) so CPU time is all the work, on one core.
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/render/episode.hpp"
#include "actionshift/render/image.hpp"
#include "actionshift/render/renderer.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/scene.hpp"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>

namespace {

using namespace actionshift;

const bool kOneThread = [] { return ::setenv("LP_NUM_THREADS", "0", 1) == 0; }();

void BM_RenderFrame320x240(benchmark::State& state) {
  benchmark::DoNotOptimize(kOneThread);
  sim::Env env(sim::EnvModel::make(sim::TaskId::kPickCube));
  env.reset(5);
  const sim::Scene scene = sim::scene_of(env);
  render::Renderer r(320, 240);
  const render::Camera cam = render::default_camera(sim::TaskId::kPickCube);
  for (auto _ : state) benchmark::DoNotOptimize(r.render(scene, cam));
}
BENCHMARK(BM_RenderFrame320x240)->Unit(benchmark::kMillisecond);

// the whole `actionshift render ... --out x.gif` work for a 50-step PickCube episode (oracle, expert)
void BM_RenderEpisode50Steps320x240(benchmark::State& state) {
  benchmark::DoNotOptimize(kOneThread);
  eval::JobRequest q;
  q.task = "pick_cube";
  q.split = "reference_seen";
  q.method.name = "oracle";
  q.episodes = 2;
  const eval::JobSpec job = eval::resolve_job(q, eval::default_resolver());
  const auto out = std::filesystem::temp_directory_path() / "actionshift_render_bench.gif";
  for (auto _ : state) {
    render::RenderedEpisode e = render::render_episode(job, 0);
    render::write_gif(out, e.frames, 10);
    state.counters["frames"] = static_cast<double>(e.frames.size());
  }
  std::filesystem::remove(out);
}
BENCHMARK(BM_RenderEpisode50Steps320x240)->Unit(benchmark::kMillisecond);

}  // namespace
