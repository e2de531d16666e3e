#include "cmd_eval.hpp"

#include "commands.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/gates.hpp"
#include "actionshift/eval/store.hpp"
#include "actionshift/eval/summary.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace actionshift::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// bad input becomes one line and exit 2; anything else propagates to main's handler
template <class F>
int guarded(std::ostream& err, F&& body) {
  try {
    return body();
  } catch (const std::invalid_argument& e) {  // InputError derives from it
    err << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

json read_json_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_json_input(ss.str(), path);
}

void ensure_parent(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
  if (ec) throw InputError(parent.string(), "", "cannot create directory: " + ec.message());
}

eval::RunResult run_with(const eval::JobSpec& job, const RunPlanOptions& o, const EpisodeFnFactory& make,
                         std::ostream& out, std::ostream& err) {
  eval::RunOptions ro;
  ro.threads = o.threads;
  ro.out_dir = o.out_dir;
  ro.progress = parse_progress_mode(o.progress);
  ro.fsync = o.fsync;
  ro.log = &err;
  const eval::EpisodeFn fn = make(job);
  const eval::RunResult r = eval::run_job(job, fn, ro);
  out << r.job_id << " " << job.task << "/" << job.split.name << "/" << job.method << " seed " << job.seed << ": "
      << (r.already_complete ? "already complete" : std::to_string(r.episodes_run) + " episodes run") << ", "
      << r.episodes_total << " in " << r.jsonl_path << "\n";
  return r;
}

}  // namespace

namespace {
// the nearest existing ancestor of `p` (or `p` itself) must be a directory
void check_ancestors(const fs::path& p, const std::string& path, const std::string& option) {
  std::error_code ec;
  for (fs::path a = p.parent_path(); !a.empty(); a = a.parent_path()) {
    if (fs::exists(a, ec)) {
      if (!fs::is_directory(a, ec)) throw InputError(path, option, a.string() + " exists and is not a directory");
      return;
    }
    if (a == a.parent_path()) return;
  }
}
}  // namespace

void check_output_file(const std::string& path, const std::string& option) {
  if (path.empty()) throw InputError(path, option, "empty path");
  std::error_code ec;
  if (path.back() == '/' || fs::is_directory(path, ec))
    throw InputError(path, option, "is a directory (expected a file path)");
  check_ancestors(fs::path(path), path, option);
}

void check_output_dir(const std::string& path, const std::string& option) {
  if (path.empty()) throw InputError(path, option, "empty path");
  std::error_code ec;
  const fs::path p(path);
  if (fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec)) throw InputError(path, option, "exists and is not a directory");
    if (::access(path.c_str(), W_OK | X_OK) != 0) throw InputError(path, option, "directory is not writable");
    return;
  }
  check_ancestors(p, path, option);
}

eval::ProgressMode parse_progress_mode(const std::string& text) {
  if (text == "auto") return eval::ProgressMode::automatic;
  if (text == "bar") return eval::ProgressMode::bar;
  if (text == "lines") return eval::ProgressMode::lines;
  if (text == "off") return eval::ProgressMode::off;
  throw InputError("--progress", "", "expected auto, bar, lines or off (got \"" + text + "\")");
}

int run_summarize(const SummarizeOptions& o, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    if (!o.out_file.empty()) check_output_file(o.out_file, "--out");
    const eval::ResultSet rs = eval::load_results(o.results_dir);
    for (const auto& note : rs.notes) err << "actionshift: note: " << note << "\n";
    if (rs.records.empty()) throw InputError(o.results_dir, "", "no episode records (*.jsonl) found");
    const auto cells = eval::summarize_records(rs.records);
    const json j = eval::summary_to_json(cells);
    if (!o.out_file.empty()) {
      ensure_parent(o.out_file);
      eval::write_json_atomic(o.out_file, j);
    }
    if (o.json) out << j.dump(2) << "\n";
    else out << eval::summary_to_markdown(cells);
    return kOk;
  });
}

int run_gate1(const Gate1Options& o, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    if (!o.verdict_file.empty()) check_output_file(o.verdict_file, "--verdict");
    const eval::ResultSet rs = eval::load_results(o.results_dir);
    for (const auto& note : rs.notes) err << "actionshift: note: " << note << "\n";
    const eval::Gate1Report report = eval::gate1(rs.records, o.samples, o.bootstrap_seed);
    if (report.cells.empty()) throw InputError(o.results_dir, "", "no oracle or no_adapt records found");
    const json j = eval::gate1_to_json(report);
    const std::string path = o.verdict_file.empty() ? (fs::path(o.results_dir) / "gate1.verdict.json").string() : o.verdict_file;
    ensure_parent(path);
    eval::write_json_atomic(path, j);
    if (o.json) out << j.dump(2) << "\n";
    else out << eval::gate1_to_markdown(report) << "verdict file: " << path << "\n";
    return report.passed ? kOk : kCheckFailed;
  });
}

int run_gate_promote(const GatePromoteOptions& o, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    if (o.candidate.empty() || o.baseline.empty() || o.candidate == o.baseline)
      throw InputError("gate promote", "--candidate/--baseline", "give two different methods");
    if (!o.verdict_file.empty()) check_output_file(o.verdict_file, "--verdict");
    const eval::ResultSet rs = eval::load_results(o.results_dir);
    for (const auto& note : rs.notes) err << "actionshift: note: " << note << "\n";
    const json j = eval::promotion_report(rs.records, o.candidate, o.baseline);
    if (j["cells"].empty())
      throw InputError(o.results_dir, "", "no (task, split) cell holds records of both " + o.candidate + " and " + o.baseline);
    const std::string path = o.verdict_file.empty()
                                 ? (fs::path(o.results_dir) / ("promotion." + o.candidate + ".vs." + o.baseline + ".json")).string()
                                 : o.verdict_file;
    ensure_parent(path);
    eval::write_json_atomic(path, j);
    if (o.json) out << j.dump(2) << "\n";
    else out << eval::promotion_to_markdown(j) << "verdict file: " << path << "\n";
    return kOk;
  });
}

int run_gate_check(const GateCheckOptions& o, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    if (o.results_dir.empty() == o.actual_file.empty())
      throw InputError("gate check", "", "give exactly one of --results DIR and --actual FILE");
    const json expected = read_json_file(o.expected_file);
    json actual;
    if (!o.actual_file.empty()) {
      actual = read_json_file(o.actual_file);
    } else {
      if (!expected.is_object() || expected.value("gate", "") != "gate1")
        throw InputError(o.expected_file, "gate",
                         "only gate1 verdicts can be recomputed from --results; use --actual FILE for other gates");
      const eval::ResultSet rs = eval::load_results(o.results_dir);
      for (const auto& note : rs.notes) err << "actionshift: note: " << note << "\n";
      actual = eval::gate1_to_json(eval::gate1(rs.records));
    }
    const auto changes = eval::compare_verdicts(expected, actual, o.expected_file);
    std::size_t regressions = 0;
    for (const auto& c : changes) {
      out << c.line << "\n";
      regressions += c.regression;
    }
    out << (regressions ? std::to_string(regressions) + " verdict regression(s)" : std::string("no verdict regressions"))
        << "\n";
    return regressions ? kCheckFailed : kOk;
  });
}

int run_plan(const PlanOptions& o, const eval::PlanResolver& resolver, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    const eval::Experiment ex = eval::load_experiment(o.experiment_file);
    const eval::Plan plan = eval::make_plan(ex, resolver);
    const std::string plan_path =
        o.plan_file.empty() ? (fs::path(o.out_dir) / (ex.name + ".plan.json")).string() : o.plan_file;
    ensure_parent(plan_path);
    eval::write_plan(plan_path, plan);
    out << "plan " << ex.name << ": " << plan.jobs.size() << " jobs -> " << plan_path << "\n";
    if (o.slurm) {
      std::error_code ec;
      fs::create_directories(o.out_dir, ec);  // Slurm does not create the --output directory
      if (ec) throw InputError(o.out_dir, "", "cannot create directory: " + ec.message());
      eval::SlurmOptions so;
      so.plan_path = fs::absolute(plan_path).string();
      so.out_dir = fs::absolute(o.out_dir).string();
      so.executable = o.executable;
      so.cpus_per_task = o.cpus_per_task;
      so.time_limit = o.time_limit;
      so.partition = o.partition;
      so.max_parallel = o.max_parallel;
      const std::string script_path =
          o.slurm_file.empty() ? (fs::path(o.out_dir) / (ex.name + ".sbatch")).string() : o.slurm_file;
      ensure_parent(script_path);
      {
        std::ofstream f(script_path, std::ios::binary | std::ios::trunc);
        f << eval::slurm_array_script(plan, so);
        if (!f) throw InputError(script_path, "", "cannot write Slurm script");
      }
      fs::permissions(script_path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, ec);
      out << "slurm array script: " << script_path << " (sbatch " << script_path << ")\n";
    }
    return kOk;
  });
}

int run_plan_jobs(const RunPlanOptions& o, const EpisodeFnFactory& make, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    check_output_dir(o.out_dir, "--out");
    const eval::Plan plan = eval::load_plan(o.plan_file);
    if (o.job_index) {
      if (*o.job_index < 0 || *o.job_index >= static_cast<std::int64_t>(plan.jobs.size()))
        throw InputError(o.plan_file, "--job-index",
                         "out of range (plan has " + std::to_string(plan.jobs.size()) + " jobs, got " +
                             std::to_string(*o.job_index) + ")");
      run_with(plan.jobs[static_cast<std::size_t>(*o.job_index)].spec, o, make, out, err);
      return kOk;
    }
    for (const auto& pj : plan.jobs) run_with(pj.spec, o, make, out, err);
    return kOk;
  });
}

int run_one_job(const eval::JobSpec& job, const RunPlanOptions& o, const EpisodeFnFactory& make, std::ostream& out,
                std::ostream& err) {
  return guarded(err, [&] {
    check_output_dir(o.out_dir, "--out");
    run_with(job, o, make, out, err);
    return kOk;
  });
}

}  // namespace actionshift::cli
