// the results report: HTML + Markdown with tables, verdicts, figures and provenance
#include "actionshift/core/input_file.hpp"
#include "actionshift/render/report.hpp"
#include "xml_escape.hpp"

#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/vocabulary.hpp"
#include "actionshift/eval/summary.hpp"
#include "actionshift/render/figures.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace actionshift::render {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string esc(const std::string& s) { return detail::xml_escape(s); }

std::string md(const std::string& s) {  // a Markdown table cell
  std::string out;
  for (const char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

json read_json(const fs::path& p) {
  json j = json::parse(read_input_file(p.string(), "a JSON file", kMaxJsonDocumentBytes), nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw InputError(p.string(), "", "not a JSON object");
  return j;
}

void write_text(const fs::path& p, const std::string& text) { write_file_atomic(p.string(), text); }

std::string str_field(const json& j, const char* key, const std::string& fallback = "-") {
  if (!j.is_object() || !j.contains(key)) return fallback;
  const json& v = j[key];
  if (v.is_string()) return v.get<std::string>();
  if (v.is_null()) return fallback;
  return v.dump();
}

struct JobRow {
  std::string id, file;
  json summary;
};

struct VerdictFile {
  std::string name;  // file name
  json doc;
};

std::string r3(double x) { return eval::fixed(x, 3); }

}  // namespace

ReportResult write_report(const std::string& results_dir, const std::string& out_dir) {
  const fs::path in(results_dir);
  if (!fs::is_directory(in)) throw InputError(results_dir, "", "not a directory");
  const eval::ResultSet results = eval::load_results(results_dir);
  if (results.records.empty()) throw InputError(results_dir, "", eval::no_records_reason(results));
  const std::vector<eval::CellSummary> cells = eval::summarize_records(results.records);

  std::vector<JobRow> jobs;
  std::vector<VerdictFile> verdicts;
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(in))
    if (e.is_regular_file()) entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  for (const auto& p : entries) {
    const std::string name = p.filename().string();
    auto ends = [&](const std::string& s) { return name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0; };
    if (ends(".summary.json")) {
      json j = read_json(p);
      jobs.push_back({str_field(j, "job_id", name.substr(0, name.size() - 13)), name, std::move(j)});
    } else if (ends(".verdict.json") || (name.rfind("promotion.", 0) == 0 && ends(".json"))) {
      json j = read_json(p);
      if (!j.contains("cells") || !j["cells"].is_object()) throw InputError(p.string(), "cells", "missing: not a verdict file");
      for (auto it = j["cells"].begin(); it != j["cells"].end(); ++it) {
        if (!it.value().is_object()) throw InputError(p.string(), "cells." + it.key(), "expected an object");
        for (const char* k : {"verdict", "decision", "reason"})
          if (it.value().contains(k) && !it.value()[k].is_string())
            throw InputError(p.string(), "cells." + it.key() + "." + k, "expected a string");
      }
      verdicts.push_back({name, std::move(j)});
    }
  }
  const json* gate1 = nullptr;
  for (const auto& v : verdicts)
    if (str_field(v.doc, "gate") == "gate1") gate1 = &v.doc;

  // output directory
  const fs::path out(out_dir);
  std::error_code ec;
  fs::create_directories(out / "figures", ec);
  if (!ec) fs::create_directories(out / "verdicts", ec);
  if (ec || !fs::is_directory(out)) throw InputError(out_dir, "--out", "cannot create the directory (" + ec.message() + ")");

  ReportResult result;
  result.summaries = jobs.size();
  result.verdicts = verdicts.size();
  result.html_path = (out / "index.html").string();
  result.markdown_path = (out / "report.md").string();

  const std::vector<Figure> figures = all_figures(cells, gate1);
  for (const auto& f : figures) {
    write_text(out / "figures" / f.name, f.svg);
    result.figures.push_back((out / "figures" / f.name).string());
  }
  write_text(out / "summary.json", eval::summary_to_json(cells).dump(2) + "\n");
  for (const auto& v : verdicts) write_text(out / "verdicts" / v.name, v.doc.dump(2) + "\n");

  // provenance: the profile from the job specs, the commit from the records' provenance.git_commit
  std::set<std::string> profiles, commits;
  for (const auto& j : jobs) {
    const json& spec = j.summary.contains("job") ? j.summary["job"] : json::object();
    if (spec.contains("profile")) profiles.insert(str_field(spec, "profile"));
  }
  std::size_t without_commit = 0;
  for (const auto& r : results.records) {
    if (r.git_commit.empty()) ++without_commit;
    else commits.insert(r.git_commit);
  }
  auto joined = [](const std::set<std::string>& s, const std::string& none) {
    if (s.empty()) return none;
    std::string out;
    for (const auto& x : s) out += (out.empty() ? "" : ", ") + x;
    return out;
  };
  const std::string profile_text = joined(profiles, "not recorded in the job specs");
  std::string commit_text = joined(commits, "not recorded in the result files");
  if (!commits.empty() && without_commit > 0)
    commit_text += " (and " + std::to_string(without_commit) + " records without one)";
  std::set<std::string> summarised;  // job ids with a row in the job table
  for (const auto& j : jobs) summarised.insert(j.id);
  std::size_t complete = 0;
  for (const auto& j : jobs)
    if (j.summary.value("complete", false)) ++complete;

  std::ostringstream h, m;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>ActionShift results: "
    << esc(in.filename().string()) << "</title>\n<style>\n"
    << "body{font-family:Helvetica,Arial,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}\n"
    << "table{border-collapse:collapse;margin:1em 0;font-size:13px}td,th{border:1px solid #ccc;padding:3px 7px;text-align:left}\n"
    << "th{background:#f0f0f0}td.n{text-align:right;font-variant-numeric:tabular-nums}code{font-size:12px}\n"
    << ".pass{color:#1a7f37;font-weight:bold}.fail{color:#c62828;font-weight:bold}figure{margin:1.5em 0}\n"
    << "figcaption{font-size:13px;color:#555}img{max-width:100%;border:1px solid #eee}\n</style></head><body>\n";
  h << "<h1>ActionShift results: <code>" << esc(results_dir) << "</code></h1>\n";
  m << "# ActionShift results: `" << results_dir << "`\n\n";

  // provenance
  h << "<h2>Provenance</h2>\n<ul>\n<li>" << results.records.size() << " episode records in " << results.files.size()
    << " JSONL files; " << jobs.size() << " job summaries (" << complete << " complete); " << verdicts.size()
    << " verdict files.</li>\n<li>Simulator profile: " << esc(profile_text) << ".</li>\n<li>Commit: " << esc(commit_text)
    << ".</li>\n<li>Every table row names the job ids it is computed from; the job table below gives each job's spec. "
    << "Recompute with <code>actionshift summarize " << esc(results_dir) << "</code>; the results summary is in "
    << "<a href=\"summary.json\">summary.json</a>.</li>\n";
  for (const auto& note : results.notes) h << "<li>Note: " << esc(note) << "</li>\n";
  h << "</ul>\n";
  m << "## Provenance\n\n- " << results.records.size() << " episode records in " << results.files.size() << " JSONL files; "
    << jobs.size() << " job summaries (" << complete << " complete); " << verdicts.size() << " verdict files.\n"
    << "- Simulator profile: " << profile_text << ".\n- Commit: " << commit_text << ".\n"
    << "- Every table row names the job ids it is computed from; the job table below gives each job's spec. "
    << "Recompute with `actionshift summarize " << results_dir << "`; the results summary is in [summary.json](summary.json).\n";
  for (const auto& note : results.notes) m << "- Note: " << note << "\n";
  m << "\n";

  // gate verdicts
  if (!verdicts.empty()) {
    h << "<h2>Gate verdicts</h2>\n";
    m << "## Gate verdicts\n\n";
    for (const auto& v : verdicts) {
      const std::string gate = str_field(v.doc, "gate", v.name);
      const bool has_passed = v.doc.contains("passed") && v.doc["passed"].is_boolean();
      const std::string overall = has_passed ? (v.doc["passed"].get<bool>() ? "passed" : "not passed") : "-";
      h << "<h3>" << esc(gate) << " (<a href=\"verdicts/" << esc(v.name) << "\">" << esc(v.name) << "</a>): <span class=\""
        << (overall == "passed" ? "pass" : "fail") << "\">" << esc(overall) << "</span></h3>\n<table><tr><th>cell</th><th>verdict</th><th>reason</th></tr>\n";
      m << "### " << gate << " ([" << v.name << "](verdicts/" << v.name << ")): " << overall << "\n\n| cell | verdict | reason |\n|---|---|---|\n";
      for (const auto& [cell, c] : v.doc["cells"].items()) {
        const std::string verdict = str_field(c, "verdict", str_field(c, "decision"));
        const std::string reason = str_field(c, "reason", "");
        h << "<tr><td>" << esc(cell) << "</td><td class=\"" << (verdict == verdict_name(Verdict::kPass) || verdict == verdict_name(Verdict::kPromote) ? "pass" : "")
          << "\">" << esc(verdict) << "</td><td>" << esc(reason) << "</td></tr>\n";
        m << "| " << md(cell) << " | " << md(verdict) << " | " << md(reason) << " |\n";
      }
      h << "</table>\n";
      m << "\n";
    }
  }

  // figures
  h << "<h2>Figures</h2>\n";
  m << "## Figures\n\n";
  if (figures.empty()) {
    h << "<p>No figure: the results hold no cell a figure needs (Gate 1 needs oracle and no_adapt on a task and split).</p>\n";
    m << "No figure: the results hold no cell a figure needs (Gate 1 needs oracle and no_adapt on a task and split).\n\n";
  }
  for (const auto& f : figures) {
    h << "<figure><a href=\"figures/" << esc(f.name) << "\"><img src=\"figures/" << esc(f.name) << "\" alt=\"" << esc(f.title)
      << "\"></a><figcaption>" << esc(f.title) << "</figcaption></figure>\n";
    m << "![" << f.title << "](figures/" << f.name << ")\n\n*" << f.title << "*\n\n";
  }

  // summary table
  h << "<h2>Results summary</h2>\n<p>success = success_once with its Wilson 95 % interval; probe = mean probe steps per episode; "
       "disp. = mean TCP translation during probes [m].</p>\n<table><tr><th>task</th><th>split</th><th>method</th><th>backbone</th>"
       "<th>n</th><th>success</th><th>Wilson 95 %</th><th>per seed</th><th>probe</th><th>disp. [m]</th><th>safety flags</th><th>jobs</th></tr>\n";
  m << "## Results summary\n\nsuccess = success_once with its Wilson 95 % interval; probe = mean probe steps per episode; "
       "disp. = mean TCP translation during probes [m].\n\n| task | split | method | backbone | n | success | Wilson 95 % | per seed | probe | disp. [m] | safety flags | jobs |\n"
       "|---|---|---|---|---:|---:|---|---|---:|---:|---|---|\n";
  for (const auto& c : cells) {
    std::string seeds, flags, job_ids, job_links;
    for (const auto& s : c.per_seed) seeds += (seeds.empty() ? "" : "/") + r3(s.rate);
    for (const auto& [f, n] : c.safety_flags) flags += (flags.empty() ? "" : ", ") + f + " " + std::to_string(n);
    if (flags.empty()) flags = "-";
    for (const auto& id : c.jobs) {
      job_ids += (job_ids.empty() ? "" : " ") + id.substr(0, 12);
      const std::string code = "<code title=\"" + esc(id) + "\">" + esc(id.substr(0, 12)) + "</code>";
      job_links += (job_links.empty() ? "" : " ") + (summarised.count(id) ? "<a href=\"#job-" + esc(id) + "\">" + code + "</a>" : code);
    }
    const std::string ci = "[" + r3(c.success_once.lower) + ", " + r3(std::min(c.success_once.upper, 1.0)) + "]";
    h << "<tr><td>" << esc(c.key.task) << "</td><td>" << esc(c.key.split) << "</td><td>" << esc(c.key.method) << "</td><td>"
      << esc(c.key.backbone) << "</td><td class=\"n\">" << c.episodes << "</td><td class=\"n\">" << r3(c.success_once.rate)
      << "</td><td>" << ci << "</td><td>" << seeds << "</td><td class=\"n\">" << eval::fixed(c.mean_probe_steps, 2)
      << "</td><td class=\"n\">" << eval::fixed(c.mean_probe_displacement, 4) << "</td><td>" << esc(flags) << "</td><td>" << job_links
      << "</td></tr>\n";
    m << "| " << md(c.key.task) << " | " << md(c.key.split) << " | " << md(c.key.method) << " | " << md(c.key.backbone) << " | "
      << c.episodes << " | " << r3(c.success_once.rate) << " | " << ci << " | " << seeds << " | " << eval::fixed(c.mean_probe_steps, 2)
      << " | " << eval::fixed(c.mean_probe_displacement, 4) << " | " << md(flags) << " | " << job_ids << " |\n";
  }
  h << "</table>\n";
  m << "\n";

  // jobs
  h << "<h2>Jobs</h2>\n<table><tr><th>job id</th><th>task</th><th>split</th><th>method</th><th>backbone</th><th>seed</th>"
       "<th>episodes</th><th>rotation</th><th>profile</th><th>state</th><th>wall time [s]</th></tr>\n";
  m << "## Jobs\n\n| job id | task | split | method | backbone | seed | episodes | rotation | profile | state | wall time [s] |\n"
       "|---|---|---|---|---|---:|---:|---|---|---|---:|\n";
  for (const auto& j : jobs) {
    const json& spec = j.summary.contains("job") ? j.summary["job"] : json::object();
    const std::string method = spec.contains("method") ? str_field(spec["method"], "name") : "-";
    const std::string backbone = spec.contains("backbone") ? str_field(spec["backbone"], "name") : "-";
    const std::string split = spec.contains("split") ? str_field(spec["split"], "name") : "-";
    const std::string wall = j.summary.contains("wall_time_s") && j.summary["wall_time_s"].is_number()
                                 ? eval::fixed(j.summary["wall_time_s"].get<double>(), 1)
                                 : "-";
    const std::string state = str_field(j.summary, "message");
    h << "<tr id=\"job-" << esc(j.id) << "\"><td><code>" << esc(j.id) << "</code></td><td>" << esc(str_field(spec, "task"))
      << "</td><td>" << esc(split) << "</td><td>" << esc(method) << "</td><td>" << esc(backbone) << "</td><td class=\"n\">"
      << esc(str_field(spec, "seed")) << "</td><td class=\"n\">" << esc(str_field(spec, "episodes")) << "</td><td>"
      << esc(str_field(spec, "rotation_mode")) << "</td><td>" << esc(str_field(spec, "profile")) << "</td><td>" << esc(state)
      << "</td><td class=\"n\">" << wall << "</td></tr>\n";
    m << "| `" << j.id << "` | " << md(str_field(spec, "task")) << " | " << md(split) << " | " << md(method) << " | " << md(backbone)
      << " | " << str_field(spec, "seed") << " | " << str_field(spec, "episodes") << " | " << md(str_field(spec, "rotation_mode"))
      << " | " << md(str_field(spec, "profile")) << " | " << md(state) << " | " << wall << " |\n";
  }
  h << "</table>\n<p>Written by <code>actionshift report</code>.</p>\n</body></html>\n";
  m << "\nWritten by `actionshift report`.\n";

  write_text(out / "index.html", h.str());
  write_text(out / "report.md", m.str());
  return result;
}

}  // namespace actionshift::render
