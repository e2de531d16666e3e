// an episode drawn step by step through the runner's own episode function
#include "actionshift/render/episode.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/render/renderer.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/scene.hpp"

#include <algorithm>

namespace actionshift::render {

namespace {

constexpr Rgb kWhite{255, 255, 255}, kAmber{255, 190, 40}, kBlue{110, 170, 255}, kGreen{90, 235, 110}, kRed{255, 90, 80};

void draw_overlay(Image& im, const std::string& label, const std::string& where, const eval::EpisodeStepView& v) {
  const int s = im.width() >= 480 ? 2 : 1;
  const int line = 9 * s;
  shade_rect(im, 0, 0, im.width(), 2 * line + 4 * s, 0.55);
  draw_text(im, 3 * s, 2 * s, label, kWhite, s);
  draw_text(im, im.width() - text_width(where, s) - 3 * s, 2 * s, where, kWhite, s);
  const std::string step = "step " + std::to_string(v.step) + "/" + std::to_string(v.horizon) + " ";
  const int y = 2 * s + line;
  draw_text(im, 3 * s, y, step, kWhite, s);
  const std::string phase = v.step == 0 ? "reset" : (v.probe ? "probe" : "act");
  draw_text(im, 3 * s + text_width(step, s), y, phase, v.step == 0 ? kWhite : (v.probe ? kAmber : kBlue), s);
  std::string state;
  Rgb color = kGreen;
  if (v.result->safety != sim::SafetyFlag::kNone) {
    state = "safety: " + std::string(sim::safety_flag_name(v.result->safety));
    color = kRed;
  } else if (v.result->success) {
    state = "success";
  }
  if (!state.empty()) draw_text(im, im.width() - text_width(state, s) - 3 * s, y, state, color, s);
}

}  // namespace

RenderedEpisode render_episode(const eval::JobSpec& job, std::int64_t episode_index, const EpisodeRenderOptions& o) {
  if (episode_index < 0 || episode_index >= job.episodes)
    throw InputError("command line", "--episode", "episode " + std::to_string(episode_index) + " is outside the job's " +
                                                      std::to_string(job.episodes) + " episodes");
  const sim::TaskId task_id = sim::parse_task(job.task);
  const Camera camera = o.camera.value_or(default_camera(task_id));
  const eval::EpisodeTask task = eval::episode_task(job, episode_index);
  const std::string label = !o.label.empty() ? o.label : (o.clean ? std::string("clean") : job.method);
  const std::string where = "c" + std::to_string(task.contract_index) + " ep" + std::to_string(task.contract_episode);

  Renderer renderer(o.width, o.height);
  RenderedEpisode out;
  eval::EpisodeHooks hooks;
  hooks.observer = [&](const eval::EpisodeStepView& v) {
    Image im = renderer.render(sim::scene_of(*v.env), camera);
    if (o.overlay) draw_overlay(im, label, where, v);
    out.frames.push_back(std::move(im));
    out.probe.push_back(v.probe);
    out.success.push_back(v.result->success);
  };
  if (o.clean) hooks.contract_override = Contract::identity();
  const eval::EpisodeFn fn = eval::make_episode_fn(job, o.episode, std::move(hooks));
  out.record = fn(task);
  eval::stamp_record(out.record, job, eval::job_id(job), task);
  return out;
}

}  // namespace actionshift::render
