#pragma once
// `actionshift render` (an episode as GIF or PNG), `actionshift montage` (renders side by side) and
// `actionshift report` (HTML + Markdown page with figures): plain functions, no CLI11 here.

#include "cmd_run.hpp"

#include "actionshift/render/episode.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace actionshift::cli {

// `actionshift render --task T --split S --method M [--contract I] [--episode E] [--camera C]
//  [--size WxH] [--frame K] [--clean] [--label L] [--no-overlay] --out FILE.gif|png`
// plus every job option of `run` (--seed, --episodes, --backbone, --pool, --params, --rotation-mode,
// --profile, --obs-noise, --calibration, --robot/--package, --policy-files) and --step-timeout.
struct RenderOptions {
  CliJobOptions job;                // the job, resolved exactly as `run` resolves it
  // --clean, --label, --no-overlay and --step-timeout (render.episode.external.step_timeout_s) bind
  // straight into the library's settings; the image size and camera are parsed into it by run_render
  render::EpisodeRenderOptions render;
  std::int64_t contract{0};         // --contract I: contract index in the split
  std::int64_t episode{0};          // --episode E: the contract's E-th episode (job episode E * contracts + I)
  std::string camera{"default"};    // --camera
  std::string size{"320x240"};      // --size WxH
  int frame{-1};                    // --frame K (PNG only): the state after K steps; -1: the last
  int delay_cs{10};                 // --delay: GIF frame time in 1/100 s (1..1000, checked by CLI11)
  std::string out;                  // --out FILE.gif|FILE.png
};
int run_render(const RenderOptions& o);

// `actionshift montage IN.gif... --out OUT.gif|png [--frame K]`: GIF renders side by side; shorter
// inputs hold their last frame. PNG output: frame K (default: the last).
struct MontageOptions {
  std::vector<std::string> inputs;
  std::string out;
  int frame{-1};
  int delay_cs{10};  // 1..1000, checked by CLI11
};
int run_montage(const MontageOptions& o);

// `actionshift report RESULTS_DIR --out DIR`
struct ReportOptions {
  std::vector<std::string> results_dirs;
  std::string out_dir;
  bool leaderboard{false};
  std::string reference{"entropy_probes"};
  bool common_episodes{false};
  std::vector<std::string> splits;  ///< --leaderboard: only these splits
  std::string command;  ///< the command line, printed on the leaderboard page
};
int run_report(const ReportOptions& o);

}  // namespace actionshift::cli
