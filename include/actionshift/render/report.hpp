#pragma once
/// \file
/// `actionshift report`: one self-contained HTML page (inline style, no scripts, no network) and
/// the same content as Markdown, from a results directory: the results summary table, every gate
/// verdict file found, the SVG figures, and the provenance of every number (the job ids behind each
/// row, each job's spec, completion and wall time, and the simulator profile and commit when the
/// result files record them).

#include <string>
#include <vector>

namespace actionshift::render {

/// What write_report wrote.
struct ReportResult {
  std::string html_path;               ///< `<out>/index.html`
  std::string markdown_path;           ///< `<out>/report.md`
  std::vector<std::string> figures;    ///< `<out>/figures/<name>.svg`, in page order
  std::size_t summaries{0};            ///< job summaries (`*.summary.json`) read
  std::size_t verdicts{0};             ///< verdict files (`*.verdict.json`, `promotion.*.json`) read
};

/// Read `results_dir` (every `*.jsonl`, `*.summary.json` and verdict file, not recursive) and write
/// `<out_dir>/index.html`, `<out_dir>/report.md`, `<out_dir>/figures/*.svg`, `<out_dir>/summary.json`
/// (the results summary) and copies of the verdict files under `<out_dir>/verdicts/`.
/// Throws actionshift::InputError for a missing or empty results directory, an unreadable or invalid
/// file (named), or an output directory that cannot be written.
ReportResult write_report(const std::string& results_dir, const std::string& out_dir);

}  // namespace actionshift::render
