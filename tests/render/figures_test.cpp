// SVG figures from summary cells, and the report page
#include "actionshift/core/error.hpp"
#include "actionshift/eval/record.hpp"
#include "actionshift/eval/summary.hpp"
#include "actionshift/render/figures.hpp"
#include "actionshift/render/report.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

namespace actionshift::render {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// records of one cell: `successes` of `n` episodes succeed, each with `probes` probe steps
std::vector<eval::EpisodeRecord> cell(const std::string& task, const std::string& split, const std::string& method, int n,
                                      int successes, int probes) {
  std::vector<eval::EpisodeRecord> out;
  for (int i = 0; i < n; ++i) {
    eval::EpisodeRecord r;
    r.job_id = std::string(63, 'a') + std::to_string(method.size() % 10);  // oracle ...6, no_adapt ...8
    r.task = task;
    r.split = split;
    r.method = method;
    r.method_variant = method;
    r.seed = 1;
    r.contract_index = i % 2;
    r.contract_sha256 = std::string(64, 'c');
    r.episode_index = i;
    r.success_once = r.success_at_end = i < successes;
    r.steps = 50;
    r.probe_steps = probes;
    r.backbone = "expert";
    r.backbone_sha256 = std::string(64, 'b');
    out.push_back(r);
  }
  return out;
}

std::vector<eval::EpisodeRecord> concat(std::initializer_list<std::vector<eval::EpisodeRecord>> parts) {
  std::vector<eval::EpisodeRecord> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

int count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t p = text.find(needle); p != std::string::npos; p = text.find(needle, p + 1)) ++n;
  return n;
}

TEST(Figures, Gate1BarsHaveHeightsOfTheRatesAndWilsonWhiskers) {
  const auto cells = eval::summarize_records(
      concat({cell("pick_cube", "seen", "oracle", 20, 20, 0), cell("pick_cube", "seen", "no_adapt", 20, 5, 0)}));
  const nlohmann::json verdict = {{"gate", "gate1"}, {"cells", {{"pick_cube/seen", {{"verdict", "fail"}}}}}};
  const auto fig = gate1_figure(cells, &verdict);
  ASSERT_TRUE(fig.has_value());
  EXPECT_EQ(fig->name, "gate1.svg");
  EXPECT_THAT(fig->svg, HasSubstr("<svg xmlns=\"http://www.w3.org/2000/svg\""));
  // plot height 240 px: a rate of 1 is a 240 px bar, 0.25 a 60 px bar
  EXPECT_THAT(fig->svg, HasSubstr("height=\"240.0\" fill=\"" + method_color("oracle") + "\""));
  EXPECT_THAT(fig->svg, HasSubstr("height=\"60.0\" fill=\"" + method_color("no_adapt") + "\""));
  EXPECT_THAT(fig->svg, HasSubstr("no_adapt pick_cube/seen: 0.250 ["));
  EXPECT_THAT(fig->svg, HasSubstr(">fail</text>"));
  EXPECT_EQ(count(fig->svg, "stroke=\"#111\""), 2 * 3);  // whisker + two caps per bar

  // no ladder without a method beyond the Gate 1 pair, no Pareto plot without a method that probes
  EXPECT_TRUE(ladder_figures(cells).empty());
  EXPECT_TRUE(pareto_figures(cells).empty());
  EXPECT_FALSE(long_lag_figure(cells).has_value());
  // a figure whose inputs are absent is skipped
  const auto only_oracle = eval::summarize_records(cell("pick_cube", "seen", "oracle", 4, 4, 0));
  EXPECT_FALSE(gate1_figure(only_oracle).has_value());
  EXPECT_TRUE(all_figures(only_oracle).empty());
}

TEST(Figures, LadderParetoAndLongLagFromTheirCells) {
  const auto cells = eval::summarize_records(concat({
      cell("push_cube", "seen", "no_adapt", 10, 0, 0), cell("push_cube", "seen", "entropy_probes", 10, 10, 6),
      cell("push_cube", "seen", "dualabi", 10, 9, 1), cell("push_cube", "seen", "fixed_probes", 10, 8, 6),
      cell("push_cube", "long_lag", "oracle", 10, 1, 0), cell("push_cube", "long_lag", "no_adapt", 10, 0, 0)}));
  const auto ladders = ladder_figures(cells);
  ASSERT_EQ(ladders.size(), 1u);  // long_lag is not a ladder
  EXPECT_EQ(ladders[0].name, "ladder_seen.svg");
  // ladder order: no_adapt before fixed_probes before entropy_probes before dualabi
  const std::string& s = ladders[0].svg;
  EXPECT_LT(s.find("<title>no_adapt"), s.find("<title>fixed_probes"));
  EXPECT_LT(s.find("<title>fixed_probes"), s.find("<title>entropy_probes"));
  EXPECT_LT(s.find("<title>entropy_probes"), s.find("<title>dualabi"));

  const auto pareto = pareto_figures(cells);
  ASSERT_EQ(pareto.size(), 1u);
  EXPECT_EQ(pareto[0].name, "pareto_push_cube.svg");
  // seen's front: no_adapt (0 probes), dualabi (1), entropy (6); fixed_probes (6 probes, 0.8) is dominated
  const std::smatch m = [&] {
    std::smatch mm;
    std::regex_search(pareto[0].svg, mm, std::regex("<polyline points=\"([^\"]*)\""));
    return mm;
  }();
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(count(m[1].str(), ","), 3);

  const auto lag = long_lag_figure(cells);
  ASSERT_TRUE(lag.has_value());
  EXPECT_THAT(lag->svg, HasSubstr("push_cube/long_lag"));
  EXPECT_EQ(all_figures(cells).size(), 4u);  // Gate 1 (the pair on long_lag), ladder, Pareto, long lag
}

TEST(Report, WritesHtmlAndMarkdownWhoseLinksAllExist) {
  const fs::path root = fs::temp_directory_path() / ("actionshift_report_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "results");
  auto recs = concat({cell("pick_cube", "seen", "oracle", 8, 8, 0), cell("pick_cube", "seen", "no_adapt", 8, 0, 0)});
  const std::string commit = "0123456789abcdef0123456789abcdef01234567";
  for (auto& r : recs)
    if (r.method == "oracle") {  // records carry provenance {actionshift_version, git_commit}; the no_adapt ones none
      r.actionshift_version = "0.1.0";
      r.git_commit = commit;
    }
  {
    // the summary below is written by hand for this test, not the oracle job's own: its records are in a file of another name,
    // so that load_results does not check them against it (records_sha256)
    std::ofstream f(root / "results" / "oracle-records.jsonl");
    for (const auto& r : recs)
      if (r.method == "oracle") f << eval::to_jsonl_line(r) << "\n";
    std::ofstream g(root / "results" / (std::string(63, 'a') + "8.jsonl"));
    for (const auto& r : recs)
      if (r.method == "no_adapt") g << eval::to_jsonl_line(r) << "\n";
    std::ofstream v(root / "results" / "gate1.verdict.json");
    v << R"({"gate":"gate1","passed":true,"cells":{"pick_cube/seen":{"verdict":"pass","reason":"oracle 1.0000, no_adapt 0.0000"}}})";
    std::ofstream s(root / "results" / (std::string(63, 'a') + "6.summary.json"));
    s << R"({"job_id":")" << std::string(63, 'a') << R"(6","job":{"task":"pick_cube","profile":"ideal","method":{"name":"oracle"}},"complete":true,"wall_time_s":1.5,"message":"complete: 8 episodes"})";
  }
  const ReportResult r = write_report((root / "results").string(), (root / "out").string());
  EXPECT_EQ(r.summaries, 1u);
  EXPECT_EQ(r.verdicts, 1u);
  ASSERT_EQ(r.figures.size(), 1u);  // Gate 1 (no ladder, and no Pareto plot: nothing probes)
  std::ifstream f(r.html_path);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string html = ss.str();
  EXPECT_THAT(html, HasSubstr("Simulator profile: ideal."));
  // the commit comes from the records' provenance.git_commit (the page said "not recorded" before)
  EXPECT_THAT(html, HasSubstr("Commit: " + commit + " (and 8 records without one)."));
  EXPECT_THAT(html, HasSubstr("oracle 1.0000, no_adapt 0.0000"));
  EXPECT_THAT(html, HasSubstr("id=\"job-" + std::string(63, 'a') + "6\""));
  // every src / href target exists (a file under out, or an element id of the page)
  const std::regex target("(?:src|href)=\"([^\"]+)\"");
  int targets = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), target); it != std::sregex_iterator(); ++it) {
    const std::string t = (*it)[1].str();
    ++targets;
    if (t[0] == '#')
      EXPECT_THAT(html, HasSubstr("id=\"" + t.substr(1) + "\"")) << t;
    else
      EXPECT_TRUE(fs::exists(root / "out" / t)) << t;
  }
  EXPECT_GE(targets, 5);  // summary.json, verdict copy, the figure's img and link, 1 job anchor
  EXPECT_TRUE(fs::exists(r.markdown_path));
  EXPECT_THAT([&] { write_report((root / "missing").string(), (root / "out").string()); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("not a directory")));
  fs::remove_all(root);
}


// several backbones in one cell: one ladder per (task, split), one line per backbone, rungs in the
// order of the paper's Fig. 4; all_figures then draws these instead of the single-backbone bars
TEST(Figures, LadderPerBackboneDrawsOneLinePerBackbone) {
  std::vector<eval::EpisodeRecord> recs;
  const std::vector<std::string> backbones = {"ppo", "mlp:configs/backbones/replicas/push_cube.ppo.seed1.asmlp"};
  for (const auto& b : backbones)
    for (const auto& [m, k] : std::vector<std::pair<std::string, int>>{{"oracle", 10}, {"no_adapt", 0}, {"entropy_probes", 8}, {"grammar_belief{probe=hold}", 5}}) {
      auto c = cell("push_cube", "reference_seen", m, 10, k, 0);
      for (auto& r : c) {
        r.backbone = b;
        r.method_variant = m;
        r.method = m.substr(0, m.find('{'));
      }
      recs.insert(recs.end(), c.begin(), c.end());
    }
  const auto cells = eval::summarize_records(recs);
  const auto figs = ladder_by_backbone_figures(cells);
  ASSERT_EQ(figs.size(), 1u);
  EXPECT_EQ(figs[0].name, "ladder_by_backbone_push_cube_reference_seen.svg");
  EXPECT_EQ(count(figs[0].svg, "<polyline"), 2);
  EXPECT_EQ(count(figs[0].svg, "<circle"), 8);
  EXPECT_THAT(figs[0].svg, HasSubstr("push_cube.ppo.seed1.asmlp"));  // a weight file by its name
  // rungs bottom to top: no_adapt, grammar, entropy, oracle
  const auto at = [&](const std::string& t) { return figs[0].svg.find(">" + t + "</text>"); };
  EXPECT_LT(at("no_adapt"), at("grammar_belief{probe=hold}"));
  EXPECT_LT(at("grammar_belief{probe=hold}"), at("entropy_probes"));
  EXPECT_LT(at("entropy_probes"), at("oracle"));
  const auto all = all_figures(cells);
  EXPECT_TRUE(std::any_of(all.begin(), all.end(), [](const Figure& f) { return f.name.starts_with("ladder_by_backbone_"); }));
  EXPECT_FALSE(std::any_of(all.begin(), all.end(), [](const Figure& f) { return f.name.starts_with("ladder_reference"); }));
  // one backbone: no such figure
  std::vector<eval::EpisodeRecord> one;
  for (const auto& r : recs)
    if (r.backbone == "ppo") one.push_back(r);
  EXPECT_TRUE(ladder_by_backbone_figures(eval::summarize_records(one)).empty());
}

}  // namespace
}  // namespace actionshift::render
