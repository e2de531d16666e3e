// SVG figures of results: grouped bars with Wilson intervals, probe-cost scatter with its Pareto front
#include "actionshift/render/figures.hpp"
#include "xml_escape.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

namespace actionshift::render {

namespace {

const std::vector<std::string>& ladder_order() {
  static const std::vector<std::string> order{"no_adapt",     "fixed_probes", "random_probes", "entropy_probes",
                                              "exact_belief", "dualabi",      "oracle"};
  return order;
}

int method_rank(const std::string& m) {
  const auto& o = ladder_order();
  const auto it = std::find(o.begin(), o.end(), m);
  return it == o.end() ? static_cast<int>(o.size()) : static_cast<int>(it - o.begin());
}

bool method_less(const std::string& a, const std::string& b) {
  const int ra = method_rank(a), rb = method_rank(b);
  return ra != rb ? ra < rb : a < b;
}

bool is_long_lag(const std::string& split) { return split.find("long_lag") != std::string::npos; }

std::string esc(const std::string& s) { return detail::xml_escape(s); }

std::string num(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", x);
  return b;
}

std::string rate3(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", x);
  return b;
}

// a minimal SVG builder
class Svg {
 public:
  Svg(double w, double h) : w_(w), h_(h) {}
  void rect(double x, double y, double w, double h, const std::string& fill, const std::string& extra = "") {
    s_ << "<rect x=\"" << num(x) << "\" y=\"" << num(y) << "\" width=\"" << num(w) << "\" height=\"" << num(h)
       << "\" fill=\"" << fill << "\"" << extra << "/>\n";
  }
  void rect_titled(double x, double y, double w, double h, const std::string& fill, const std::string& title) {
    s_ << "<rect x=\"" << num(x) << "\" y=\"" << num(y) << "\" width=\"" << num(w) << "\" height=\"" << num(h)
       << "\" fill=\"" << fill << "\"><title>" << esc(title) << "</title></rect>\n";
  }
  void line(double x1, double y1, double x2, double y2, const std::string& stroke, double width = 1.0,
            const std::string& extra = "") {
    s_ << "<line x1=\"" << num(x1) << "\" y1=\"" << num(y1) << "\" x2=\"" << num(x2) << "\" y2=\"" << num(y2)
       << "\" stroke=\"" << stroke << "\" stroke-width=\"" << num(width) << "\"" << extra << "/>\n";
  }
  void text(double x, double y, const std::string& t, const std::string& anchor = "start", int size = 12,
            const std::string& extra = "") {
    s_ << "<text x=\"" << num(x) << "\" y=\"" << num(y) << "\" font-size=\"" << size << "\" text-anchor=\"" << anchor
       << "\"" << extra << ">" << esc(t) << "</text>\n";
  }
  void circle(double x, double y, double r, const std::string& fill, const std::string& title) {
    s_ << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\"" << num(r) << "\" fill=\"" << fill
       << "\" stroke=\"#222\" stroke-width=\"0.8\"><title>" << esc(title) << "</title></circle>\n";
  }
  void raw(const std::string& t) { s_ << t; }
  std::string str() const {
    std::ostringstream o;
    o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(w_) << "\" height=\"" << num(h_)
      << "\" viewBox=\"0 0 " << num(w_) << " " << num(h_) << "\" font-family=\"Helvetica, Arial, sans-serif\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << s_.str() << "</svg>\n";
    return o.str();
  }

 private:
  double w_, h_;
  std::ostringstream s_;
};

// success axis [0, 1] on the left of a plot area
void success_axis(Svg& svg, double x0, double y0, double w, double h, const std::string& label) {
  for (int i = 0; i <= 4; ++i) {
    const double v = 0.25 * i, y = y0 + h - v * h;
    svg.line(x0, y, x0 + w, y, "#ddd");
    svg.text(x0 - 6, y + 4, rate3(v).substr(0, 4), "end", 11);
  }
  svg.line(x0, y0, x0, y0 + h, "#333");
  svg.line(x0, y0 + h, x0 + w, y0 + h, "#333");
  svg.text(14, y0 + h / 2, label, "middle", 12, " transform=\"rotate(-90 14 " + num(y0 + h / 2) + ")\"");
}

struct Bar {
  std::string series;  // legend entry (method)
  const eval::CellSummary* cell;
};
struct Group {
  std::string label;   // x label (task, or task/split)
  std::string note;    // under the label (e.g. a verdict)
  std::vector<Bar> bars;
};

// grouped bars of success_once with Wilson 95 % whiskers
std::string grouped_bars(const std::string& title, const std::vector<Group>& groups, const std::vector<std::string>& series) {
  const double bar_w = 16, group_gap = 28, left = 64, top = 44, plot_h = 240;
  double plot_w = 0;
  for (const auto& g : groups) plot_w += static_cast<double>(std::max<std::size_t>(g.bars.size(), 1)) * bar_w + group_gap;
  plot_w = std::max(plot_w, 240.0);
  const double legend_w = 150;
  Svg svg(left + plot_w + legend_w, top + plot_h + 70);
  svg.text(left, 24, title, "start", 14, " font-weight=\"bold\"");
  success_axis(svg, left, top, plot_w, plot_h, "success (Wilson 95 %)");
  double x = left + group_gap / 2;
  for (const auto& g : groups) {
    const double gx0 = x;
    for (const auto& b : g.bars) {
      const auto& s = b.cell->success_once;
      const double y = top + plot_h - std::clamp(s.rate, 0.0, 1.0) * plot_h;
      svg.rect_titled(x + 1, y, bar_w - 2, top + plot_h - y, method_color(b.series),
                      b.series + " " + b.cell->key.task + "/" + b.cell->key.split + ": " + rate3(s.rate) + " [" +
                          rate3(s.lower) + ", " + rate3(s.upper) + "], n = " + std::to_string(s.total));
      const double ylo = top + plot_h - std::clamp(s.lower, 0.0, 1.0) * plot_h;
      const double yhi = top + plot_h - std::clamp(s.upper, 0.0, 1.0) * plot_h;
      const double cx = x + bar_w / 2;
      svg.line(cx, ylo, cx, yhi, "#111", 1.2);
      svg.line(cx - 4, ylo, cx + 4, ylo, "#111", 1.2);
      svg.line(cx - 4, yhi, cx + 4, yhi, "#111", 1.2);
      x += bar_w;
    }
    const double gc = (gx0 + x) / 2;
    svg.text(gc, top + plot_h + 16, g.label, "middle", 11);
    if (!g.note.empty()) svg.text(gc, top + plot_h + 30, g.note, "middle", 11, " font-style=\"italic\"");
    x += group_gap;
  }
  // legend
  double ly = top + 6;
  for (const auto& s : series) {
    svg.rect(left + plot_w + 16, ly - 9, 12, 12, method_color(s));
    svg.text(left + plot_w + 34, ly + 1, s, "start", 12);
    ly += 18;
  }
  return svg.str();
}

std::string safe_name(const std::string& s) {
  std::string out;
  for (const char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-') ? c : '_';
  return out;
}

const eval::CellSummary* find_cell(const std::vector<eval::CellSummary>& cells, const std::string& task, const std::string& split,
                                   const std::string& method) {
  for (const auto& c : cells)
    if (c.key.task == task && c.key.split == split && c.key.method == method) return &c;
  return nullptr;
}

}  // namespace

std::string method_color(const std::string& method) {
  static const std::map<std::string, std::string> colors{
      {"no_adapt", "#d62728"},     {"fixed_probes", "#ff9f1c"}, {"random_probes", "#bcbd22"},
      {"entropy_probes", "#1f77b4"}, {"exact_belief", "#9467bd"}, {"dualabi", "#17becf"},
      {"oracle", "#2ca02c"}};
  const auto it = colors.find(method);
  if (it != colors.end()) return it->second;
  static const char* extra[] = {"#8c564b", "#e377c2", "#7f7f7f", "#393b79", "#637939"};
  std::size_t h = 0;
  for (const char c : method) h = h * 31 + static_cast<unsigned char>(c);
  return extra[h % 5];
}

std::optional<Figure> gate1_figure(const std::vector<eval::CellSummary>& cells, const nlohmann::json* verdict) {
  std::vector<Group> groups;
  std::set<std::pair<std::string, std::string>> seen;
  for (const auto& c : cells) {
    const auto ts = std::make_pair(c.key.task, c.key.split);
    if (seen.count(ts)) continue;
    const auto* o = find_cell(cells, c.key.task, c.key.split, "oracle");
    const auto* n = find_cell(cells, c.key.task, c.key.split, "no_adapt");
    if (!o || !n) continue;
    seen.insert(ts);
    Group g;
    g.label = c.key.task + "/" + c.key.split;
    if (verdict && verdict->contains("cells") && (*verdict)["cells"].contains(g.label)) {
      const nlohmann::json& cell = (*verdict)["cells"][g.label];
      if (cell.is_object() && cell.contains("verdict") && cell["verdict"].is_string()) g.note = cell["verdict"].get<std::string>();
    }
    g.bars = {{"oracle", o}, {"no_adapt", n}};
    groups.push_back(std::move(g));
  }
  if (groups.empty()) return std::nullopt;
  return Figure{"gate1.svg", "Gate 1: privileged oracle vs no adaptation (success_once, Wilson 95 %), verdict under each cell",
                grouped_bars("Gate 1: oracle vs no_adapt", groups, {"oracle", "no_adapt"})};
}

std::vector<Figure> ladder_figures(const std::vector<eval::CellSummary>& cells) {
  std::map<std::string, std::vector<const eval::CellSummary*>> by_split;
  for (const auto& c : cells)
    if (!is_long_lag(c.key.split)) by_split[c.key.split].push_back(&c);
  std::vector<Figure> out;
  for (const auto& [split, cs] : by_split) {
    std::set<std::string, decltype(&method_less)> methods(&method_less);
    for (const auto* c : cs) methods.insert(c->key.method);
    const bool beyond_gate1 = std::any_of(methods.begin(), methods.end(), [](const std::string& m) { return m != "oracle" && m != "no_adapt"; });
    if (!beyond_gate1) continue;
    std::map<std::string, Group> groups;
    for (const auto* c : cs) {
      auto& g = groups[c->key.task];
      g.label = c->key.task;
      g.bars.push_back({c->key.method, c});
    }
    std::vector<Group> ordered;
    for (auto& [task, g] : groups) {
      std::sort(g.bars.begin(), g.bars.end(), [](const Bar& a, const Bar& b) { return method_less(a.series, b.series); });
      ordered.push_back(g);
    }
    const std::vector<std::string> series(methods.begin(), methods.end());
    out.push_back({"ladder_" + safe_name(split) + ".svg", "Adaptation ladder on " + split + ": success per method and task",
                   grouped_bars("Adaptation ladder: " + split, ordered, series)});
  }
  return out;
}

namespace {
// the ladder of the paper's Fig. 4, bottom to top: no adaptation, grammar knowledge, pool belief, the
// ceiling; a label sorts by its base name, variants after the base
int ladder_rung(const std::string& label) {
  static const std::vector<std::string> order{"no_adapt",     "osi",          "probe_osi",      "recurrent_osi",
                                              "grammar_belief", "fixed_probes", "random_probes", "entropy_probes",
                                              "exact_belief", "dualabi",      "oracle"};
  const std::string base = label.substr(0, label.find('{'));
  const auto it = std::find(order.begin(), order.end(), base);
  return it == order.end() ? static_cast<int>(order.size()) : static_cast<int>(it - order.begin());
}
bool rung_less(const std::string& a, const std::string& b) {
  const int ra = ladder_rung(a), rb = ladder_rung(b);
  return ra != rb ? ra < rb : a < b;
}
// a backbone's legend name: a weight file by its file name
std::string backbone_label(const std::string& b) {
  const auto slash = b.rfind('/');
  return slash == std::string::npos ? b : b.substr(slash + 1);
}
const char* kLineColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f"};
}  // namespace

std::vector<Figure> ladder_by_backbone_figures(const std::vector<eval::CellSummary>& cells) {
  std::map<std::pair<std::string, std::string>, std::vector<const eval::CellSummary*>> by_cell;
  for (const auto& c : cells)
    if (!is_long_lag(c.key.split)) by_cell[{c.key.task, c.key.split}].push_back(&c);
  std::vector<Figure> out;
  for (const auto& [ts, cs] : by_cell) {
    std::set<std::string> backbones;
    std::set<std::string, decltype(&rung_less)> methods(&rung_less);
    for (const auto* c : cs) {
      backbones.insert(c->key.backbone);
      methods.insert(c->key.method);
    }
    if (backbones.size() < 2 || methods.size() < 2) continue;
    const std::vector<std::string> ms(methods.begin(), methods.end());
    const double left = 64, top = 44, plot_h = 240, step = 62, legend_w = 300;
    const double plot_w = std::max(240.0, step * static_cast<double>(ms.size()));
    Svg svg(left + plot_w + legend_w, top + plot_h + 120);
    svg.text(left, 24, "The ladder per backbone: " + ts.first + " / " + ts.second, "start", 14, " font-weight=\"bold\"");
    success_axis(svg, left, top, plot_w, plot_h, "success (Wilson 95 %)");
    const auto px = [&](std::size_t i) { return left + step * (static_cast<double>(i) + 0.5); };
    const auto py = [&](double v) { return top + plot_h - std::clamp(v, 0.0, 1.0) * plot_h; };
    for (std::size_t i = 0; i < ms.size(); ++i)
      svg.text(px(i), top + plot_h + 14, ms[i], "end", 10, " transform=\"rotate(-35 " + num(px(i)) + " " + num(top + plot_h + 14) + ")\"");
    std::size_t k = 0;
    for (const auto& b : backbones) {
      const std::string color = kLineColors[k % (sizeof kLineColors / sizeof *kLineColors)];
      const double jitter = (static_cast<double>(k) - static_cast<double>(backbones.size() - 1) / 2.0) * 5.0;
      std::string points;
      for (std::size_t i = 0; i < ms.size(); ++i) {
        const auto it = std::find_if(cs.begin(), cs.end(), [&](const auto* c) { return c->key.backbone == b && c->key.method == ms[i]; });
        if (it == cs.end()) continue;
        const auto& s = (*it)->success_once;
        const double x = px(i) + jitter;
        svg.line(x, py(s.lower), x, py(s.upper), color, 1.2);
        svg.circle(x, py(s.rate), 3.5, color, backbone_label(b) + " " + ms[i] + ": " + rate3(s.rate) + " [" + rate3(s.lower) + ", " +
                                                  rate3(s.upper) + "], n = " + std::to_string(s.total));
        points += (points.empty() ? "" : " ") + num(x) + "," + num(py(s.rate));
      }
      svg.raw("<polyline points=\"" + points + "\" fill=\"none\" stroke=\"" + color + "\" stroke-width=\"1.5\"/>\n");
      const double ly = top + 6 + 18 * static_cast<double>(k);
      svg.line(left + plot_w + 16, ly - 3, left + plot_w + 32, ly - 3, color, 2.5);
      svg.text(left + plot_w + 38, ly + 1, backbone_label(b), "start", 11);
      ++k;
    }
    out.push_back({"ladder_by_backbone_" + safe_name(ts.first) + "_" + safe_name(ts.second) + ".svg",
                   "The ladder per backbone on " + ts.first + " / " + ts.second +
                       ": success per method (rungs in the order of the paper's Fig. 4), one line per backbone",
                   svg.str()});
  }
  return out;
}

std::optional<Figure> long_lag_figure(const std::vector<eval::CellSummary>& cells) {
  std::vector<eval::CellSummary> lag;
  for (const auto& c : cells)
    if (is_long_lag(c.key.split)) lag.push_back(c);
  if (lag.empty()) return std::nullopt;
  // all long-lag splits in one figure: groups are task/split
  std::map<std::string, Group> groups;
  std::set<std::string, decltype(&method_less)> methods(&method_less);
  for (const auto& c : lag) {
    const std::string label = c.key.task + "/" + c.key.split;
    auto& g = groups[label];
    g.label = label;
    methods.insert(c.key.method);
  }
  for (const auto& c : cells)
    if (is_long_lag(c.key.split)) groups[c.key.task + "/" + c.key.split].bars.push_back({c.key.method, &c});
  std::vector<Group> ordered;
  for (auto& [label, g] : groups) {
    std::sort(g.bars.begin(), g.bars.end(), [](const Bar& a, const Bar& b) { return method_less(a.series, b.series); });
    ordered.push_back(g);
  }
  return Figure{"long_lag.svg", "Long lag: success per method (no encoder can act in the past)",
                grouped_bars("Long lag", ordered, std::vector<std::string>(methods.begin(), methods.end()))};
}

std::vector<Figure> pareto_figures(const std::vector<eval::CellSummary>& cells) {
  std::map<std::string, std::vector<const eval::CellSummary*>> by_task;
  for (const auto& c : cells) by_task[c.key.task].push_back(&c);
  std::vector<Figure> out;
  for (const auto& [task, cs] : by_task) {
    std::set<std::string> methods;
    for (const auto* c : cs) methods.insert(c->key.method);
    const bool probes = std::any_of(cs.begin(), cs.end(), [](const auto* c) { return c->mean_probe_steps > 0.0; });
    if (methods.size() < 2 || !probes) continue;  // a probe-cost plot needs a method that probes
    double xmax = 1.0;
    for (const auto* c : cs) xmax = std::max(xmax, c->mean_probe_steps);
    xmax = std::ceil(xmax * 1.1);
    std::vector<std::string> splits;
    for (const auto* c : cs)
      if (std::find(splits.begin(), splits.end(), c->key.split) == splits.end()) splits.push_back(c->key.split);
    const double left = 64, top = 44, w = 420, h = 260;
    Svg svg(left + w + 190, top + h + 60);
    svg.text(left, 24, "Success vs probe cost: " + task, "start", 14, " font-weight=\"bold\"");
    success_axis(svg, left, top, w, h, "success (Wilson 95 %)");
    for (int i = 0; i <= 4; ++i) {
      const double v = xmax * i / 4.0, x = left + w * i / 4.0;
      svg.line(x, top + h, x, top + h + 4, "#333");
      char b[32];
      std::snprintf(b, sizeof b, "%.1f", v);
      svg.text(x, top + h + 16, b, "middle", 11);
    }
    svg.text(left + w / 2, top + h + 36, "mean probe steps per episode", "middle", 12);
    auto px = [&](double v) { return left + w * v / xmax; };
    auto py = [&](double v) { return top + h - std::clamp(v, 0.0, 1.0) * h; };
    // Pareto front per split: not dominated (fewer or equal probes and higher or equal success, one strictly)
    for (const auto& split : splits) {
      std::vector<const eval::CellSummary*> pts;
      for (const auto* c : cs)
        if (c->key.split == split) pts.push_back(c);
      std::vector<const eval::CellSummary*> front;
      for (const auto* a : pts) {
        bool dominated = false;
        for (const auto* b : pts)
          if (b != a && b->mean_probe_steps <= a->mean_probe_steps && b->success_once.rate >= a->success_once.rate &&
              (b->mean_probe_steps < a->mean_probe_steps || b->success_once.rate > a->success_once.rate))
            dominated = true;
        if (!dominated) front.push_back(a);
      }
      std::sort(front.begin(), front.end(), [](auto* a, auto* b) { return a->mean_probe_steps < b->mean_probe_steps; });
      if (front.size() > 1) {
        std::string pts_attr;
        for (const auto* f : front) pts_attr += num(px(f->mean_probe_steps)) + "," + num(py(f->success_once.rate)) + " ";
        svg.raw("<polyline points=\"" + pts_attr + "\" fill=\"none\" stroke=\"#888\" stroke-dasharray=\"4 3\"/>\n");
      }
    }
    for (const auto* c : cs) {
      const double x = px(c->mean_probe_steps);
      svg.line(x, py(c->success_once.lower), x, py(c->success_once.upper), "#444", 1.0);
      const std::size_t si = static_cast<std::size_t>(std::find(splits.begin(), splits.end(), c->key.split) - splits.begin());
      const std::string tip = c->key.method + " on " + c->key.split + ": success " + rate3(c->success_once.rate) +
                              ", probe steps " + rate3(c->mean_probe_steps);
      if (si % 2 == 0) {
        svg.circle(x, py(c->success_once.rate), 5, method_color(c->key.method), tip);
      } else {  // second, fourth ... split: squares
        svg.raw("<rect x=\"" + num(x - 4.5) + "\" y=\"" + num(py(c->success_once.rate) - 4.5) +
                "\" width=\"9\" height=\"9\" fill=\"" + method_color(c->key.method) +
                "\" stroke=\"#222\" stroke-width=\"0.8\"><title>" + esc(tip) + "</title></rect>\n");
      }
    }
    double ly = top + 6;
    std::vector<std::string> ms(methods.begin(), methods.end());
    std::sort(ms.begin(), ms.end(), method_less);
    for (const auto& m : ms) {
      svg.circle(left + w + 22, ly - 3, 5, method_color(m), m);
      svg.text(left + w + 34, ly + 1, m, "start", 12);
      ly += 18;
    }
    ly += 8;
    for (std::size_t i = 0; i < splits.size(); ++i) {
      svg.text(left + w + 16, ly + 1, (i % 2 == 0 ? "o  " : "[] ") + splits[i], "start", 12);
      ly += 18;
    }
    svg.text(left + w + 16, ly + 8, "dashed: Pareto front", "start", 11, " fill=\"#666\"");
    out.push_back({"pareto_" + safe_name(task) + ".svg",
                   "Success vs mean probe steps on " + task + " (each point a split and method; dashed: Pareto front per split)",
                   svg.str()});
  }
  return out;
}

std::vector<Figure> all_figures(const std::vector<eval::CellSummary>& cells, const nlohmann::json* gate1_verdict) {
  std::vector<Figure> out;
  if (auto g = gate1_figure(cells, gate1_verdict)) out.push_back(std::move(*g));
  // results of several backbones in one cell: one ladder per cell with a line per backbone (the bar
  // ladders and Pareto plots draw one backbone per cell)
  auto by_backbone = ladder_by_backbone_figures(cells);
  if (!by_backbone.empty()) {
    for (auto& f : by_backbone) out.push_back(std::move(f));
    if (auto l = long_lag_figure(cells)) out.push_back(std::move(*l));
    return out;
  }
  for (auto& f : ladder_figures(cells)) out.push_back(std::move(f));
  for (auto& f : pareto_figures(cells)) out.push_back(std::move(f));
  if (auto l = long_lag_figure(cells)) out.push_back(std::move(*l));
  return out;
}

}  // namespace actionshift::render
