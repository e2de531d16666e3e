#pragma once
/// \file
/// Rendering one episode of a job exactly as the runner runs it: the same episode function
/// (eval::make_episode_fn, observed after the reset and after every step), the same episode task
/// (eval::episode_task: contract slot and seed), and the same record stamping.

#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/record.hpp"
#include "actionshift/render/camera.hpp"
#include "actionshift/render/image.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace actionshift::render {

/// How to draw an episode.
struct EpisodeRenderOptions {
  int width{320};                 ///< [px]
  int height{240};                ///< [px]
  std::optional<Camera> camera;   ///< default: default_camera(task)
  bool overlay{true};             ///< draw the step, phase (reset / probe / act), success and label
  std::string label;              ///< first overlay line (default: the method name, "clean" with `clean`)
  /// Run the backbone with the identity contract instead of the split's (same episode seed and
  /// initial state): the clean reference panel. The record is then not one the runner writes.
  bool clean{false};
  /// Run-time options of the episode function, as `run` passes them (an external backbone's step
  /// timeout, a calibration file): they change no result, so the record is the runner's.
  eval::EpisodeFnOptions episode;
};

/// A rendered episode.
struct RenderedEpisode {
  eval::EpisodeRecord record;     ///< outcome, stamped like the runner's record of the same episode
  std::vector<Image> frames;      ///< frames[k]: the state after k control steps (frames[0]: after reset)
  std::vector<bool> probe;        ///< probe[k]: the action that led to frames[k] was a probe (probe[0] = false)
  std::vector<bool> success;      ///< success[k]: the task's success predicate held in frames[k]
};

/// Run and draw episode `episode_index` of `job`. Throws actionshift::InputError for an episode
/// index outside the job and whatever eval::make_episode_fn throws for an unresolvable job.
RenderedEpisode render_episode(const eval::JobSpec& job, std::int64_t episode_index, const EpisodeRenderOptions& options = {});

}  // namespace actionshift::render
