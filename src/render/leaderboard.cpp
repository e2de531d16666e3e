// the leaderboard page: every method label against a reference method, cell by cell, from compare's numbers
#include "actionshift/render/leaderboard.hpp"

#include "actionshift/adapt/plugin.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/compare.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/provenance.hpp"
#include "actionshift/eval/statistics.hpp"
#include "actionshift/eval/summary.hpp"
#include "xml_escape.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

namespace actionshift::render {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using CellId = std::tuple<std::string, std::string, std::string>;  // task, split, backbone

std::string r3(double x) { return eval::fixed(x, 3); }
std::string signed3(double x) { return (x >= 0 ? "+" : "") + eval::fixed(x, 3); }

struct Row {
  std::string label, rung, kind;
  std::map<CellId, json> cells;        // compare's cell
  std::map<CellId, json> comparisons;  // compare's comparison with the reference
  double mean_success{0.0};
};

// a user method's rung and kind, from the summary of one of its jobs (the job spec names them)
std::pair<std::string, std::string> declared_rung(const std::vector<std::string>& dirs, const json& jobs) {
  for (const auto& id : jobs) {
    for (const auto& dir : dirs) {
      const fs::path p = fs::path(dir) / eval::summary_file_name(id.get<std::string>());
      std::error_code ec;
      if (!fs::is_regular_file(p, ec)) continue;
      const json s = parse_json_input(read_input_file(p.string(), "job summary"), p.string());
      if (!s.is_object() || !s.contains("job") || !s["job"].contains("method")) continue;
      const json& m = s["job"]["method"];
      if (m.contains("plugin") && m["plugin"].is_object())
        return {m["plugin"].value("rung", "?"), m["plugin"].value("kind", "?")};
      return {"?", "?"};
    }
  }
  return {"?", "?"};
}

std::pair<std::string, std::string> rung_of(const std::string& label, const std::vector<std::string>& dirs, const json& jobs) {
  const std::string base = eval::method_base_name(label);
  const auto& builtin = adapt::method_names();
  if (std::find(builtin.begin(), builtin.end(), base) != builtin.end())
    return {std::string(adapt::rung_name(adapt::method_rung(base))), "built-in"};
  return declared_rung(dirs, jobs);
}

void write_text(const fs::path& p, const std::string& text) { write_file_atomic(p.string(), text); }

std::string md_cell(const std::string& s) {
  std::string out;
  for (const char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

}  // namespace

LeaderboardResult write_leaderboard(const LeaderboardOptions& o) {
  if (o.results_dirs.empty()) throw InputError("leaderboard", "results", "name at least one results directory");
  // the labels and cells present, to choose the pairs (every label against the reference where both ran)
  std::map<std::string, std::set<CellId>> where;
  std::set<std::string> profiles;
  std::set<std::uint64_t> seeds;
  std::size_t records = 0;
  for (const auto& dir : o.results_dirs) {
    const eval::ResultSet rs = eval::load_results(dir);
    if (rs.records.empty()) throw InputError(dir, "", eval::no_records_reason(rs));
    records += rs.records.size();
    for (const auto& r : rs.records) {
      where[r.method_variant].insert({r.task, r.split, r.backbone});
      profiles.insert(r.profile);
      seeds.insert(r.seed);
    }
  }
  const auto ref = where.find(o.reference);
  if (ref == where.end()) {
    std::string known;
    for (const auto& [label, cells] : where) known += (known.empty() ? "" : ", ") + label;
    throw InputError("leaderboard", "--reference", "no cell holds '" + o.reference + "' (labels found: " + known + ")");
  }
  std::vector<eval::ComparisonPair> pairs;
  for (const auto& [label, cells] : where) {
    if (label == o.reference) continue;
    const bool shared = std::any_of(cells.begin(), cells.end(), [&](const CellId& c) { return ref->second.count(c) > 0; });
    if (shared) pairs.push_back(eval::ComparisonPair{label, o.reference});
  }
  const json cmp = eval::compare_directories(o.results_dirs, pairs, eval::builtin_paper_numbers(), o.common_episodes);

  std::map<std::string, Row> rows;
  std::set<CellId> columns;
  for (const auto& c : cmp.at("cells")) {
    const CellId id{c.at("task").get<std::string>(), c.at("split").get<std::string>(), c.at("backbone").get<std::string>()};
    if (!ref->second.count(id)) continue;  // the board's cells are the reference's
    if (!o.splits.empty() && std::find(o.splits.begin(), o.splits.end(), std::get<1>(id)) == o.splits.end()) continue;
    columns.insert(id);
    Row& row = rows[c.at("method").get<std::string>()];
    row.label = c.at("method").get<std::string>();
    row.cells[id] = c;
  }
  for (const auto& k : cmp.at("comparisons")) {
    const CellId id{k.at("task").get<std::string>(), k.at("split").get<std::string>(), k.at("backbone").get<std::string>()};
    if (!columns.count(id)) continue;
    rows[k.at("candidate").get<std::string>()].comparisons[id] = k;
  }
  std::vector<Row> order;
  for (auto& [label, row] : rows) {
    double sum = 0.0;
    for (const auto& [id, c] : row.cells) sum += c.at("success_once").at("rate").get<double>();
    row.mean_success = row.cells.empty() ? 0.0 : sum / static_cast<double>(row.cells.size());
    const json jobs = row.cells.empty() ? json::array() : row.cells.begin()->second.at("jobs");
    std::tie(row.rung, row.kind) = rung_of(label, o.results_dirs, jobs);
    order.push_back(row);
  }
  std::stable_sort(order.begin(), order.end(), [](const Row& a, const Row& b) { return a.mean_success > b.mean_success; });

  const eval::Provenance& prov = eval::build_provenance();
  const std::string commit = prov.git_commit.empty() ? "unknown" : prov.git_commit;
  const std::string command = o.command.empty() ? "actionshift report --leaderboard" : o.command;
  // the columns grouped: one table per (task, split), a column pair per backbone
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> groups;
  std::set<std::string> backbones;
  for (const auto& c : columns) {
    groups[{std::get<0>(c), std::get<1>(c)}].push_back(std::get<2>(c));
    backbones.insert(std::get<2>(c));
  }
  const auto success_text = [](const json& w) {
    return r3(w.at("rate").get<double>()) + " [" + r3(w.at("lower").get<double>()) + ", " + r3(w.at("upper").get<double>()) +
           "] n=" + std::to_string(w.at("total").get<std::int64_t>());
  };
  const auto delta_text = [](const json& k) {
    const json& d = k.at("difference");
    return signed3(d.at("estimate").get<double>()) + " [" + signed3(d.at("lower").get<double>()) + ", " +
           signed3(d.at("upper").get<double>()) + "] " + k.at("promotion").at("verdict").get<std::string>();
  };
  const auto delta_class = [](const json& k) -> std::string {
    const json& d = k.at("difference");
    if (!d.at("excludes_zero").get<bool>()) return "";
    return d.at("estimate").get<double>() > 0 ? "up" : "down";
  };

  std::int64_t min_n = -1, max_n = 0;
  for (const auto& row : order)
    for (const auto& [id, c] : row.cells) {
      const auto n = c.at("episodes").get<std::int64_t>();
      min_n = min_n < 0 ? n : std::min(min_n, n);
      max_n = std::max(max_n, n);
    }
  std::string profile_list, seed_list;
  for (const auto& p : profiles) profile_list += (profile_list.empty() ? "" : ", ") + p;
  for (const auto& sd : seeds) seed_list += (seed_list.empty() ? "" : ", ") + std::to_string(sd);
  const std::string runs = "Simulator profile " + profile_list + "; seeds " + seed_list + "; " +
                           (min_n == max_n ? std::to_string(max_n) : std::to_string(min_n) + " to " + std::to_string(max_n)) +
                           " episodes per cell (pooled over the seeds).";
  std::ostringstream md, html;
  const std::string intro =
      "Every method label of the results against `" + o.reference + "`, on each (task, split, backbone) where `" + o.reference +
      "` ran. Success is `success_once` with its 95 % Wilson interval and n; Δ is the paired bootstrap difference from `" +
      o.reference + "` with its 95 % interval over the same episodes (same seed, contract and initial state), followed by the "
      "promotion verdict of `actionshift gate promote`; \"paper\" is the paper's success for the cell (Table 5 for the PPO "
      "backbone; configs/paper/numbers.json), set beside ours for the paper's methods only. A difference whose interval "
      "includes 0 does not rank two methods. The "
      "intervals treat episodes as independent, but the contracts of one block share their initial state, so they are somewhat "
      "too narrow (docs/formats.md, \"Comparison\").";
  md << "# Leaderboard\n\n" << intro << "\n\n"
     << "Made by `" << command << "` at commit `" << commit << "` from " << records << " records in " << o.results_dirs.size()
     << " director" << (o.results_dirs.size() == 1 ? "y" : "ies") << ". " << runs
     << " Per-seed counts and the job ids of every cell are in leaderboard.json (`board[].cells[].per_seed`, `jobs`).\n\n";
  html << "<!doctype html><html><head><meta charset=\"utf-8\"><title>ActionShift leaderboard</title><style>"
       << "body{font-family:sans-serif;margin:2em;max-width:90em}table{border-collapse:collapse;margin-bottom:1.5em}"
       << "td,th{border:1px solid #ccc;padding:.3em .6em;text-align:right}td:first-child,th:first-child{text-align:left}"
       << ".ref{background:#eef}.up{color:#060;font-weight:bold}.down{color:#a00;font-weight:bold}small{color:#555}</style></head><body>"
       << "<h1>Leaderboard</h1><p>" << detail::xml_escape(intro) << "</p><p><small>Made by <code>" << detail::xml_escape(command)
       << "</code> at commit <code>" << detail::xml_escape(commit) << "</code> from " << records << " records. "
       << detail::xml_escape(runs) << "</small></p>";

  // overall: mean success per backbone and how the paired differences fall
  md << "## Overall\n\n| method | rung | kind |";
  html << "<h2>Overall</h2><table><tr><th>method</th><th>rung</th><th>kind</th>";
  for (const auto& b : backbones) {
    md << " mean success, " << md_cell(b) << " (cells) |";
    html << "<th>mean success, " << detail::xml_escape(b) << " (cells)</th>";
  }
  md << " Δ vs " << md_cell(o.reference) << ": better / worse / not separated |\n|---|---|---|";
  html << "<th>&Delta; vs " << detail::xml_escape(o.reference) << ": better / worse / not separated</th></tr>";
  for (std::size_t i = 0; i < backbones.size(); ++i) md << "---|";
  md << "---|\n";
  json board = json::array();
  for (const auto& row : order) {
    const bool is_ref = row.label == o.reference;
    md << "| " << md_cell(is_ref ? "**" + row.label + "**" : row.label) << " | " << row.rung << " | " << row.kind << " |";
    html << "<tr" << (is_ref ? " class=\"ref\"" : "") << "><td><code>" << detail::xml_escape(row.label) << "</code></td><td>"
         << detail::xml_escape(row.rung) << "</td><td>" << detail::xml_escape(row.kind) << "</td>";
    json entry = {{"method", row.label}, {"rung", row.rung}, {"kind", row.kind}, {"mean_success", row.mean_success},
                  {"cells", json::array()}};
    for (const auto& b : backbones) {
      double sum = 0.0;
      int n = 0;
      for (const auto& [id, c] : row.cells)
        if (std::get<2>(id) == b) {
          sum += c.at("success_once").at("rate").get<double>();
          ++n;
        }
      const std::string t = n ? r3(sum / n) + " (" + std::to_string(n) + ")" : "–";
      md << " " << t << " |";
      html << "<td>" << t << "</td>";
    }
    int better = 0, worse = 0, same = 0;
    for (const auto& [id, k] : row.comparisons) {
      const std::string cls = delta_class(k);
      (cls == "up" ? better : cls == "down" ? worse : same) += 1;
    }
    const std::string counts = is_ref ? "reference" : std::to_string(better) + " / " + std::to_string(worse) + " / " + std::to_string(same);
    md << " " << counts << " |\n";
    html << "<td>" << counts << "</td></tr>";
    for (const auto& [id, c] : row.cells) {
      const auto k = row.comparisons.find(id);
      entry["cells"].push_back({{"task", std::get<0>(id)}, {"split", std::get<1>(id)}, {"backbone", std::get<2>(id)},
                                {"success_once", c.at("success_once")}, {"per_seed", c.at("per_seed")}, {"jobs", c.at("jobs")},
                                {"difference", k != row.comparisons.end() ? k->second.at("difference") : json(nullptr)},
                                {"promotion", k != row.comparisons.end() ? k->second.at("promotion") : json(nullptr)}});
    }
    board.push_back(entry);
  }
  md << "\n";
  html << "</table>";

  // one table per (task, split)
  for (const auto& [ts, bbs] : groups) {
    const std::string title = ts.first + " / " + ts.second;
    md << "## " << title << "\n\n| method |";
    html << "<h2>" << detail::xml_escape(title) << "</h2><table><tr><th>method</th>";
    for (const auto& b : bbs) {
      md << " " << md_cell(b) << " | paper | Δ vs " << md_cell(o.reference) << ", " << md_cell(b) << " |";
      html << "<th>" << detail::xml_escape(b) << "</th><th>paper</th><th>&Delta; vs " << detail::xml_escape(o.reference) << ", "
           << detail::xml_escape(b) << "</th>";
    }
    md << "\n|---|";
    for (std::size_t i = 0; i < bbs.size(); ++i) md << "---|---|---|";
    md << "\n";
    html << "</tr>";
    for (const auto& row : order) {
      bool any = false;
      for (const auto& b : bbs) any = any || row.cells.count({ts.first, ts.second, b});
      if (!any) continue;
      const bool is_ref = row.label == o.reference;
      md << "| " << md_cell(is_ref ? "**" + row.label + "**" : row.label) << " |";
      html << "<tr" << (is_ref ? " class=\"ref\"" : "") << "><td><code>" << detail::xml_escape(row.label) << "</code></td>";
      for (const auto& b : bbs) {
        const CellId id{ts.first, ts.second, b};
        const auto cell = row.cells.find(id);
        const auto k = row.comparisons.find(id);
        const std::string s = cell != row.cells.end() ? success_text(cell->second.at("success_once")) : "–";
        const std::string d = k != row.comparisons.end() ? delta_text(k->second) : (is_ref ? "reference" : "–");
        // the paper's success for this cell (configs/paper/numbers.json, through compare), when it has one
        std::string paper = "–";
        if (cell != row.cells.end() && cell->second.at("paper").contains("success_once"))
          paper = r3(cell->second.at("paper").at("success_once").at("value").get<double>());
        md << " " << s << " | " << paper << " | " << md_cell(d) << " |";
        html << "<td>" << detail::xml_escape(s) << "</td><td>" << paper << "</td><td><span class=\""
             << (k != row.comparisons.end() ? delta_class(k->second) : "") << "\">" << detail::xml_escape(d) << "</span></td>";
      }
      md << "\n";
      html << "</tr>";
    }
    md << "\n";
    html << "</table>";
  }
  md << "Rungs: what the runner handed the method (`pool`: the declared pool, the calibration and the grammar's grids; "
        "`grammar`: the calibration and the grids; `none`: nothing more; `oracle`: the true contract). Kind: `built-in`, or "
        "how a user method entered (`cpp`, `python`, `external`; docs/methods.md).\n";
  html << "<p><small>Rungs: what the runner handed the method (pool: the declared pool, the calibration and the grammar's "
          "grids; grammar: the calibration and the grids; none: nothing more; oracle: the true contract). Kind: built-in, or "
          "how a user method entered (cpp, python, external).</small></p></body></html>\n";

  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec) throw InputError(o.out_dir, "--out", "cannot create directory (" + ec.message() + ")");
  LeaderboardResult r;
  r.markdown_path = (fs::path(o.out_dir) / "leaderboard.md").string();
  r.html_path = (fs::path(o.out_dir) / "leaderboard.html").string();
  r.json_path = (fs::path(o.out_dir) / "leaderboard.json").string();
  // the board's numbers and what they were computed from (the full comparison is `actionshift compare`'s)
  json doc = {{"reference", o.reference}, {"command", command}, {"commit", commit}, {"inputs", cmp.at("inputs")},
              {"bootstrap", cmp.at("bootstrap")}, {"board", board}};
  write_text(r.markdown_path, md.str());
  write_text(r.html_path, html.str());
  write_text(r.json_path, doc.dump(1) + "\n");
  r.methods = order.size();
  r.cells = columns.size();
  return r;
}

}  // namespace actionshift::render
