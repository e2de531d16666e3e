// CLI11 registration of render, montage and report (cmd_render.cpp implements them)
#include "cli_common.hpp"
#include "cmd_render.hpp"

#include <iostream>

namespace actionshift::cli {

// a GIF frame's time: 1/100 s to 10 s (render and montage)
const auto kGifDelay = CLI::Range(1, 1000);

void register_render_commands(CLI::App& app, CliContext& ctx) {
  // ---- render | montage | report (render layer)
  auto& render_o = ctx.make<cli::RenderOptions>();
  auto* render = app.add_subcommand(
      "render",
      "Render one episode of a job headless (OSMesa) exactly as `run` runs it: same job id, contract, episode\n"
      "seed, initial state and outcome as that episode's JSONL record, which is printed as one JSON line.\n"
      "Writes an animated GIF (every step) or a PNG (one frame) with an overlay of the step, the phase\n"
      "(reset / probe / act) and success. Episode E of contract I is the one of block E (the job's episodes\n"
      "E * contracts ... E * contracts + contracts - 1, in a seeded order) that runs contract I.");
  add_job_options(ctx, render, render_o.job, /*required=*/true);
  render->add_option("--step-timeout", render_o.render.episode.external.step_timeout_s, "Seconds an external:<command> backbone may take per step (as for run)")
      ->check(CLI::Range(0.001, 86400.0) & kNotNan)
      ->capture_default_str();
  render->add_option("--contract", render_o.contract, "Contract index in the split")->capture_default_str();
  render->add_option("--episode", render_o.episode, "The contract's episode (0 = its first)")->capture_default_str();
  render->add_option("--camera", render_o.camera,
                     "default (the task's, like ManiSkill's human-render camera), front, side, top, or\n"
                     "EX,EY,EZ,TX,TY,TZ[,FOV_DEG] (eye, target [m], vertical field of view)")
      ->capture_default_str();
  render->add_option("--size", render_o.size, "Image size WIDTHxHEIGHT")->capture_default_str();
  render->add_option("--frame", render_o.frame, "PNG only: the state after this many steps (-1: the last)")->capture_default_str();
  render->add_option("--delay", render_o.delay_cs, "GIF: hundredths of a second per frame")->check(kGifDelay)->capture_default_str();
  render->add_flag("--clean", render_o.render.clean, "Same episode seed with the identity contract (the clean reference panel)");
  render->add_option("--label", render_o.render.label, "Overlay title (default: the method, or clean)");
  render->add_flag("--no-overlay{false}", render_o.render.overlay, "No overlay");
  render->add_option("--out", render_o.out, "Output FILE.gif or FILE.png")->required();
  render->callback([&] { ctx.action = [&] { return cli::run_render(render_o); }; });

  auto& montage_o = ctx.make<cli::MontageOptions>();
  auto* montage = app.add_subcommand(
      "montage", "Place GIF renders side by side (shorter ones hold their last frame): an animated GIF, or one\n"
                 "frame as PNG (e.g. the clean / no_adapt / adapted triptych).");
  montage->add_option("inputs", montage_o.inputs, "Input GIF files, left to right")->required();
  montage->add_option("--out", montage_o.out, "Output FILE.gif or FILE.png")->required();
  montage->add_option("--frame", montage_o.frame, "PNG only: frame index (-1: the last)")->capture_default_str();
  montage->add_option("--delay", montage_o.delay_cs, "GIF: hundredths of a second per frame")->check(kGifDelay)->capture_default_str();
  montage->callback([&] { ctx.action = [&] { return cli::run_montage(montage_o); }; });

  auto& report_o = ctx.make<cli::ReportOptions>();
  auto* report = app.add_subcommand(
      "report", "Write a self-contained HTML page (index.html) and Markdown (report.md) for a results directory:\n"
                "the results summary table, gate verdicts, SVG figures (Gate 1, adaptation ladders, probe-cost\n"
                "Pareto, long lag; a figure whose inputs are absent is skipped) and the provenance of every number.");
  report->add_option("results", report_o.results_dirs,
                     "Results directory (with --leaderboard: one or more, merged as `compare` merges them)")->required();
  report->add_option("--out", report_o.out_dir, "Output directory")->required();
  report->add_flag("--leaderboard", report_o.leaderboard,
                   "Write the leaderboard instead (leaderboard.md, .html, .json): every method label against\n"
                   "--reference on each (task, split, backbone) where both ran: success with its Wilson interval,\n"
                   "the paired bootstrap difference and the promotion verdict; a method of your own is one more row");
  report->add_option("--reference", report_o.reference, "--leaderboard: the method every row is compared with")
      ->capture_default_str();
  report->add_option("--splits", report_o.splits, "--leaderboard: only these splits' cells (default: every split)")
      ->delimiter(',');
  report->add_flag("--common-episodes", report_o.common_episodes,
                   "--leaderboard: pair only the episodes both cells hold (as `compare --common-episodes`)");
  report->callback([&] {
    report_o.command = command_line(ctx.argc, ctx.argv);
    ctx.action = [&] { return cli::run_report(report_o); };
  });
}

}  // namespace actionshift::cli
