// render, montage and report: thin bindings of the render layer to the command line
#include "cmd_render.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/render/episode.hpp"
#include "actionshift/render/image.hpp"
#include "actionshift/render/leaderboard.hpp"
#include "actionshift/render/report.hpp"
#include "actionshift/sim/task.hpp"
#include "commands.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace actionshift::cli {

namespace {

namespace fs = std::filesystem;

enum class Format { kGif, kPng };

// the output path must end in .gif or .png and be writable; checked before anything runs
Format check_output(const std::string& out) {
  if (out.empty()) throw InputError("command line", "--out", "missing (FILE.gif or FILE.png)");
  const fs::path p(out);
  const std::string ext = p.extension().string();
  if (ext != ".gif" && ext != ".png") throw InputError(out, "--out", "must end in .gif or .png");
  if (fs::is_directory(p)) throw InputError(out, "--out", "is a directory");
  std::error_code ec;
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  if (ec) throw InputError(out, "--out", "cannot create its directory (" + ec.message() + ")");
  const bool existed = fs::exists(p);
  {
    std::ofstream probe(p, std::ios::binary | std::ios::app);
    if (!probe) throw InputError(out, "--out", "cannot write file");
  }
  if (!existed) fs::remove(p, ec);
  return ext == ".gif" ? Format::kGif : Format::kPng;
}

std::pair<int, int> parse_size(const std::string& s) {
  const auto x = s.find('x');
  int w = 0, h = 0;
  bool ok = x != std::string::npos;
  if (ok) {
    const auto r1 = std::from_chars(s.data(), s.data() + x, w);
    const auto r2 = std::from_chars(s.data() + x + 1, s.data() + s.size(), h);
    ok = r1.ec == std::errc() && r1.ptr == s.data() + x && r2.ec == std::errc() && r2.ptr == s.data() + s.size();
  }
  if (!ok || w < 16 || h < 16 || w > 4096 || h > 4096)
    throw InputError("command line", "--size", "'" + s + "' is not WIDTHxHEIGHT with sides in 16..4096");
  return {w, h};
}

const render::Image& pick_frame(const std::vector<render::Image>& frames, int k) {
  if (k < -1 || k >= static_cast<int>(frames.size()))
    throw InputError("command line", "--frame", std::to_string(k) + " is outside 0.." + std::to_string(frames.size() - 1));
  return k < 0 ? frames.back() : frames[static_cast<std::size_t>(k)];
}

void write_frames(const std::string& out, Format f, std::vector<render::Image> frames, int frame, int delay_cs) {
  if (f == Format::kPng) {
    render::write_png(out, pick_frame(frames, frame));
    return;
  }
  const render::Image last = frames.back();
  for (int i = 0; i < 10; ++i) frames.push_back(last);  // hold the outcome for a second
  render::write_gif(out, frames, delay_cs);
}

}  // namespace

int run_render(const RenderOptions& o) {
  try {
    const Format format = check_output(o.out);
    const auto [w, h] = parse_size(o.size);
    eval::JobSpec job;
    render::EpisodeRenderOptions ro = o.render;
    resolve_cli_job(o.job, job, ro.episode);
    ro.width = w;
    ro.height = h;
    ro.camera = render::parse_camera(o.camera, sim::parse_task(job.task));
    if (o.contract < 0 || o.contract >= job.split.contracts)
      throw InputError("command line", "--contract", std::to_string(o.contract) + " is outside the split's " +
                                                         std::to_string(job.split.contracts) + " contracts");
    if (o.episode < 0) throw InputError("command line", "--episode", "must be >= 0");
    // the job's episode that runs contract I in block E: the contracts of a block run in a seeded order
    // (eval::deal_permutation), so it is not E * contracts + I
    const auto order = eval::deal_permutation(job.seed, job.split.contracts, o.episode);
    const std::int64_t index =
        o.episode * job.split.contracts + (std::find(order.begin(), order.end(), o.contract) - order.begin());
    if (index >= job.episodes)
      throw InputError("command line", "--episode", "contract " + std::to_string(o.contract) + " has no episode " +
                                                        std::to_string(o.episode) + " in a job of " +
                                                        std::to_string(job.episodes) + " episodes (--episodes)");
    render::RenderedEpisode r = render::render_episode(job, index, ro);
    write_frames(o.out, format, std::move(r.frames), o.frame, o.delay_cs);
    // the outcome, as the runner's record of this episode (a `--clean` render is not a runner record)
    nlohmann::json line = eval::to_json(r.record);
    line["rendered"] = o.out;
    line["clean"] = ro.clean;
    std::cout << line.dump() << "\n";
    return kOk;
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

int run_montage(const MontageOptions& o) {
  try {
    const Format format = check_output(o.out);
    if (o.inputs.empty()) throw InputError("command line", "inputs", "no GIF to place side by side");
    // every panel is decoded whole before the montage: bounded, as its GIFs are (8192 px a side)
    if (o.inputs.size() > 16) throw InputError("command line", "inputs", "at most 16 GIFs side by side (got " + std::to_string(o.inputs.size()) + ")");
    std::vector<std::vector<render::Image>> panels;
    std::size_t longest = 0;
    for (const std::string& in : o.inputs) {
      panels.push_back(render::read_gif(in));
      longest = std::max(longest, panels.back().size());
    }
    std::vector<render::Image> frames;
    for (std::size_t k = 0; k < longest; ++k) {
      std::vector<render::Image> row;
      for (const auto& p : panels) row.push_back(p[std::min(k, p.size() - 1)]);
      frames.push_back(render::side_by_side(row));
    }
    if (format == Format::kPng) {
      render::write_png(o.out, pick_frame(frames, o.frame));
    } else {
      render::write_gif(o.out, frames, o.delay_cs);
    }
    std::cout << "montage: " << o.inputs.size() << " panels, " << frames.size() << " frames -> " << o.out << "\n";
    return kOk;
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

int run_report(const ReportOptions& o) {
  try {
    if (o.leaderboard) {
      render::LeaderboardOptions lo;
      lo.results_dirs = o.results_dirs;
      lo.out_dir = o.out_dir;
      lo.reference = o.reference;
      lo.common_episodes = o.common_episodes;
      lo.splits = o.splits;
      lo.command = o.command;
      const render::LeaderboardResult r = render::write_leaderboard(lo);
      std::cout << "leaderboard: " << r.markdown_path << ", " << r.html_path << " and " << r.json_path << " ("
                << r.methods << " methods, " << r.cells << " cells)\n";
      return kOk;
    }
    if (o.results_dirs.size() != 1)
      throw InputError("report", "results", "give one results directory (several only with --leaderboard)");
    if (o.reference != "entropy_probes" || o.common_episodes || !o.splits.empty())
      throw InputError("report", o.common_episodes ? "--common-episodes" : !o.splits.empty() ? "--splits" : "--reference",
                       "applies to --leaderboard only");
    const render::ReportResult r = render::write_report(o.results_dirs.front(), o.out_dir);
    std::cout << "report: " << r.html_path << " and " << r.markdown_path << " (" << counted(r.figures.size(), "figure") << ", "
              << r.summaries << " job summaries)\n";
    return kOk;
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

}  // namespace actionshift::cli
