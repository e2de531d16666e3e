#pragma once
/// \file
/// Figures of results as SVG text written directly: no plotting package (the figures are bars,
/// points and a few lines), vector output that stays sharp at any zoom, and a format every browser
/// and Markdown viewer displays. Each figure is drawn from the results summary cells
/// (eval::summarize_records, the content of `actionshift summarize --json`).

#include "actionshift/eval/summary.hpp"

#include <nlohmann/json_fwd.hpp>

#include <optional>
#include <string>
#include <vector>

namespace actionshift::render {

/// One figure: a file name (no directory) and its SVG text.
struct Figure {
  std::string name;     ///< e.g. "gate1.svg"
  std::string title;    ///< one-line caption
  std::string svg;      ///< the document
};

/// Gate 1: per (task, split), oracle and no_adapt success_once with Wilson 95 % intervals, and the
/// verdict of that cell when `gate1_verdict` (a gate1.verdict.json document) holds it. Empty when no
/// cell has both methods.
std::optional<Figure> gate1_figure(const std::vector<eval::CellSummary>& cells, const nlohmann::json* gate1_verdict = nullptr);

/// The adaptation ladder of one split: per task, one bar per method (ladder order: no_adapt,
/// fixed/random/entropy probes, exact belief, DualABI, oracle, then any other) with Wilson intervals.
/// One figure per split that is not a long-lag split and holds at least one method besides the
/// Gate 1 pair.
std::vector<Figure> ladder_figures(const std::vector<eval::CellSummary>& cells);

/// Probe cost against success: per task, one point per (split, method) at (mean probe steps,
/// success_once) with its Wilson interval, and the Pareto front (no point has both fewer probe
/// steps and higher success). One figure per task with at least two methods, one of which probes.
std::vector<Figure> pareto_figures(const std::vector<eval::CellSummary>& cells);

/// Long lag: per task, one bar per method on the splits whose name contains "long_lag". Empty when
/// there are none.
std::optional<Figure> long_lag_figure(const std::vector<eval::CellSummary>& cells);

/// The ladder per backbone (the paper's Fig. 4 for each of several backbones): per (task, split) that
/// two or more backbones hold (not long lag), success_once with Wilson intervals per method in rung
/// order (no adaptation, identifiers, grammar belief, pool belief, DualABI, oracle; variants after
/// their base), one line per backbone on shared axes.
std::vector<Figure> ladder_by_backbone_figures(const std::vector<eval::CellSummary>& cells);

/// Every figure the cells support, in the order Gate 1, ladders, Pareto, long lag; where a cell holds
/// several backbones, the ladders per backbone instead of the bar ladders and Pareto plots.
std::vector<Figure> all_figures(const std::vector<eval::CellSummary>& cells, const nlohmann::json* gate1_verdict = nullptr);

/// Display colour of a method (#rrggbb), the same in every figure.
std::string method_color(const std::string& method);

}  // namespace actionshift::render
