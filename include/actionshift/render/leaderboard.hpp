#pragma once
/// \file `actionshift report --leaderboard`: one page (Markdown + self-contained HTML + JSON) ranking
/// every method label found in the results directories against a reference method, cell by cell
/// (task, split, backbone), with the numbers of `actionshift compare`: each cell's success and Wilson
/// interval, the paired bootstrap difference from the reference and the promotion verdict. A method of
/// your own (docs/methods.md) is one more row.

#include <cstddef>
#include <string>
#include <vector>

namespace actionshift::render {

/// What write_leaderboard reads and writes.
struct LeaderboardOptions {
  std::vector<std::string> results_dirs;   ///< results directories (their records are merged as `compare` merges them)
  std::string out_dir;                     ///< where leaderboard.{md,html,json} are written
  std::string reference{"entropy_probes"};  ///< every other label is compared with this one, paired, cell by cell
  bool common_episodes{false};             ///< pair only the episodes both cells hold (`compare --common-episodes`)
  std::vector<std::string> splits;         ///< only these splits' cells (empty: every split)
  std::string command;                     ///< the command line that made the page (printed on it)
};

/// What write_leaderboard wrote.
struct LeaderboardResult {
  std::string markdown_path, html_path, json_path;
  std::size_t methods{0};  ///< rows
  std::size_t cells{0};    ///< (task, split, backbone) columns
};

/// Writes `<out>/leaderboard.md` (an overall table, then one table per (task, split) with a column pair per
/// backbone), `<out>/leaderboard.html` and `<out>/leaderboard.json` (per row: its
/// rung, kind and each cell's Wilson interval, per-seed counts, job ids, paired difference and verdict). Rows are sorted by their
/// mean success over the cells they have; a method's rung is the built-in's or, for a user method, the
/// one its job declares. Throws InputError for a directory without records, a reference label found in
/// no cell, or as eval::compare_records.
LeaderboardResult write_leaderboard(const LeaderboardOptions& options);

}  // namespace actionshift::render
