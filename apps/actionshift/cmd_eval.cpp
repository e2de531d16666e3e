#include "cmd_eval.hpp"

#include "actionshift/eval/experiment_yaml.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/plan_io.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/eval/slurm.hpp"

#include "commands.hpp"

#include "actionshift/adapt/plugin.hpp"
#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/external_method.hpp"
#include "actionshift/eval/gates.hpp"
#include "actionshift/eval/store.hpp"
#include "actionshift/eval/summary.hpp"
#include "actionshift/policy/external.hpp"
#include "actionshift/policy/line_process.hpp"

#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

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
  return parse_json_input(read_input_file(path, "a JSON file", kMaxJsonDocumentBytes), path);
}

void ensure_parent(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
  if (ec) throw InputError(parent.string(), "", "cannot create directory: " + ec.message());
}

// Ctrl-C (SIGINT) and SIGTERM (what Slurm sends at a time limit) during a job: the first stops it
// after the episodes already finished, with the summary saying where (exit 130, re-run to resume);
// a second one ends the process at once. Signals ignored when the process started stay ignored.
// The first also reaches external policies at once (one blocked in a step is not waited for: its
// group is killed when the job stops); the second kills their process groups before the process ends.
std::atomic<bool> g_interrupt{false};
static_assert(std::atomic<bool>::is_always_lock_free);

extern "C" void on_interrupt_signal(int sig) {
  if (g_interrupt.exchange(true)) {
    policy::kill_external_policies();
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
  policy::interrupt_external_policies();
}

class InterruptHandlers {
 public:
  InterruptHandlers() {
    g_interrupt = false;
    policy::clear_external_interrupt();
    install(SIGINT, old_int_, has_int_);
    install(SIGTERM, old_term_, has_term_);
  }
  ~InterruptHandlers() {
    if (has_int_) sigaction(SIGINT, &old_int_, nullptr);
    if (has_term_) sigaction(SIGTERM, &old_term_, nullptr);
  }
  InterruptHandlers(const InterruptHandlers&) = delete;
  InterruptHandlers& operator=(const InterruptHandlers&) = delete;

 private:
  static void install(int sig, struct sigaction& old, bool& has) {
    if (sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) return;
    struct sigaction sa {};
    sa.sa_handler = on_interrupt_signal;
    sigemptyset(&sa.sa_mask);
    has = sigaction(sig, &sa, nullptr) == 0;
  }
  struct sigaction old_int_ {}, old_term_ {};
  bool has_int_{false}, has_term_{false};
};

// While a job runs, the process is the subreaper of its descendants (Linux, PR_SET_CHILD_SUBREAPER):
// a process an external policy started and moved out of its process group (setsid) is re-parented
// here, not to init, when its parent exits. Once the job's policies are gone (their groups killed),
// every remaining child is such a leftover: it is killed (with its group, when it leads one) and
// reaped, and the count noted on stderr. The runner starts no other child processes.
class PolicyLeftovers {
 public:
  explicit PolicyLeftovers(std::ostream& err) : err_(err) { subreaper_ = prctl(PR_SET_CHILD_SUBREAPER, 1) == 0; }
  ~PolicyLeftovers() {
    if (!subreaper_) return;
    int killed = 0;
    // members of a policy group killed a moment ago may have been re-parented here before they die:
    // reap what has died for up to 100 ms before killing (and counting) what is still alive
    for (int wait = 0; wait < 10; ++wait) {
      bool alive = false;
      for (const auto& [pid, zombie] : children_of(getpid())) {
        if (zombie) waitpid(pid, nullptr, 0);
        alive = alive || (!zombie && !policy::is_line_process_group(pid));
      }
      if (!alive) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    // a killed leftover's own children are re-parented here in turn: a few rounds
    for (int round = 0; round < 100; ++round) {
      const std::vector<std::pair<pid_t, bool>> children = children_of(getpid());
      if (children.empty()) break;
      bool any = false;
      for (const auto& [pid, zombie] : children) {
        // a live external method (kept for the next job of this command) is not a leftover
        if (!zombie && policy::is_line_process_group(pid)) continue;
        any = true;
        if (!zombie) {
          if (getpgid(pid) == pid) kill(-pid, SIGKILL);
          if (kill(pid, SIGKILL) == 0) ++killed;
        }
        waitpid(pid, nullptr, 0);
      }
      if (!any) break;
    }
    prctl(PR_SET_CHILD_SUBREAPER, 0);
    if (killed > 0)
      err_ << "actionshift: note: killed " << killed << (killed == 1 ? " process" : " processes")
           << " an external policy left behind outside its process group (setsid?)\n";
  }
  PolicyLeftovers(const PolicyLeftovers&) = delete;
  PolicyLeftovers& operator=(const PolicyLeftovers&) = delete;

 private:
  // the children of `parent` from /proc/<pid>/stat (pid, is a zombie)
  static std::vector<std::pair<pid_t, bool>> children_of(pid_t parent) {
    std::vector<std::pair<pid_t, bool>> out;
    std::error_code ec;
    fs::directory_iterator it("/proc", ec), end;
    for (; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
      std::ifstream in(it->path() / "stat");
      std::string stat;
      if (!std::getline(in, stat)) continue;
      const auto paren = stat.rfind(')');  // the command name may hold spaces and parentheses
      if (paren == std::string::npos) continue;
      std::istringstream rest(stat.substr(paren + 1));
      char state = 0;
      long ppid = 0;
      if (rest >> state >> ppid && ppid == parent) out.emplace_back(static_cast<pid_t>(std::stol(name)), state == 'Z');
    }
    return out;
  }
  std::ostream& err_;
  bool subreaper_{false};
};

eval::RunResult run_with(const eval::JobSpec& job, const RunPlanOptions& o, const EpisodeFnFactory& make,
                         std::ostream& out, std::ostream& err) {
  const PolicyLeftovers leftovers(err);  // destroyed last: after the job's policies
  const InterruptHandlers handlers;
  eval::RunOptions ro;
  ro.interrupted = [] { return g_interrupt.load(); };
  ro.threads = o.threads;
  ro.out_dir = o.out_dir;
  ro.progress = parse_progress_mode(o.progress);
  ro.fsync = o.fsync;
  ro.log = &err;
  eval::EpisodeFn fn;
  try {
    fn = make(job);  // starts an external policy (its hello may wait for the hello timeout)
  } catch (const std::runtime_error&) {
    if (g_interrupt.load()) throw eval::Interrupted("interrupted before the first episode");
    throw;
  }
  const eval::RunResult r = eval::run_job(job, fn, ro);
  out << r.job_id << " " << job.task << "/" << job.split.name << "/" << job.method << " seed " << job.seed << ": "
      << (r.already_complete ? "already complete" : std::to_string(r.episodes_run) + " episodes run") << ", "
      << r.episodes_total << " in " << r.jsonl_path << "\n";
  return r;
}

// the overall position in a plan, one line on stderr before each job (not with --progress off)
void announce(const eval::PlannedJob& pj, std::size_t total, const RunPlanOptions& o, std::ostream& err) {
  if (o.progress == "off") return;
  err << "actionshift: job " << pj.index + 1 << "/" << total << ": " << pj.job_id.substr(0, 12) << " " << pj.spec.task
      << "/" << pj.spec.split.name << "/" << pj.spec.method << " seed " << pj.spec.seed << "\n";
  err.flush();
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

eval::ProgressMode parse_progress_mode(const std::string& text) { return eval::parse_progress_mode(text, "command line", "--progress"); }

int run_summarize(const SummarizeOptions& o, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    if (!o.out_file.empty()) check_output_file(o.out_file, "--out");
    const eval::ResultSet rs = eval::load_results(o.results_dir);
    for (const auto& note : rs.notes) err << "actionshift: note: " << note << "\n";
    if (rs.records.empty()) throw InputError(o.results_dir, "", eval::no_records_reason(rs));
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
    // cells are keyed by the canonical variant label: `entropy_probes{budget=6}` is `entropy_probes`
    const std::string candidate = eval::canonical_method_label(o.candidate), baseline = eval::canonical_method_label(o.baseline);
    if (candidate == baseline) throw InputError("gate promote", "--candidate/--baseline", "both name " + candidate + ": give two different methods");
    const json j = eval::promotion_report(rs.records, candidate, baseline);
    if (j["cells"].empty())
      throw InputError(o.results_dir, "", "no (task, split) cell holds records of both " + candidate + " and " + baseline);
    const std::string path = o.verdict_file.empty()
                                 ? (fs::path(o.results_dir) / ("promotion." + candidate + ".vs." + baseline + ".json")).string()
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
      const std::string gate = expected.is_object() && expected.contains("gate") && expected["gate"].is_string()
                                   ? expected["gate"].get<std::string>()
                                   : std::string();
      if (gate != "gate1" && gate != "promotion")
        throw InputError(o.expected_file, "gate",
                         "only gate1 and promotion verdicts can be recomputed from --results; use --actual FILE for other gates");
      const eval::ResultSet rs = eval::load_results(o.results_dir);
      for (const auto& note : rs.notes) err << "actionshift: note: " << note << "\n";
      if (gate == "gate1") {
        actual = eval::gate1_to_json(eval::gate1(rs.records));
      } else {
        for (const char* k : {"candidate", "baseline"})
          if (!expected.contains(k) || !expected[k].is_string()) throw InputError(o.expected_file, k, "missing method name");
        actual = eval::promotion_report(rs.records, expected["candidate"].get<std::string>(), expected["baseline"].get<std::string>());
      }
    }
    const auto changes = eval::compare_verdicts(expected, actual, o.expected_file,
                                                o.actual_file.empty() ? "verdicts recomputed from " + o.results_dir : o.actual_file);
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

std::string resolve_executable(const std::string& executable) {
  std::error_code ec;
  fs::path p;
  if (executable.empty()) {
    p = fs::read_symlink("/proc/self/exe", ec);
    if (ec) throw InputError("/proc/self/exe", "--executable", "cannot find this binary's path; give --executable");
  } else if (executable.find('/') != std::string::npos) {
    p = fs::absolute(executable, ec);
  } else {
    const char* path_env = std::getenv("PATH");
    std::string dirs = path_env ? path_env : "";
    std::size_t pos = 0;
    while (p.empty() && pos <= dirs.size()) {
      auto colon = dirs.find(':', pos);
      if (colon == std::string::npos) colon = dirs.size();
      const fs::path cand = fs::path(dirs.substr(pos, colon - pos)) / executable;
      if (colon > pos && fs::is_regular_file(cand, ec) && ::access(cand.c_str(), X_OK) == 0) p = fs::absolute(cand, ec);
      pos = colon + 1;
    }
    if (p.empty()) throw InputError(executable, "--executable", "not found on PATH; give a path");
  }
  p = p.lexically_normal();
  if (!fs::is_regular_file(p, ec) || ::access(p.c_str(), X_OK) != 0)
    throw InputError(p.string(), "--executable", "not an executable file");
  return p.string();
}

unsigned cluster_max_array_size() {
  FILE* pipe = ::popen("command -v scontrol >/dev/null 2>&1 && timeout 20 scontrol show config 2>/dev/null", "r");
  if (!pipe) return eval::kDefaultMaxArraySize;
  std::string text;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) text.append(buf, n);
  const int rc = ::pclose(pipe);
  if (rc != 0) return eval::kDefaultMaxArraySize;
  return eval::parse_max_array_size(text).value_or(eval::kDefaultMaxArraySize);
}

int run_plan(const PlanOptions& o, const eval::PlanResolver& resolver, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    const eval::Experiment ex = eval::load_experiment(o.experiment_file);
    // an external method of the experiment is registered while its jobs are made (its identity is hashed
    // into them; the jobs then carry its command, rung, version and files)
    std::vector<adapt::MethodRegistration> external;
    for (std::size_t i = 0; i < ex.methods.size(); ++i) {
      const eval::MethodEntry& m = ex.methods[i];
      if (!m.name.starts_with("external:") || adapt::find_method_plugin(m.name)) continue;
      const std::string field = "methods[" + std::to_string(i) + "]";
      try {
        external.push_back(eval::register_external_method(m.name.substr(9), adapt::parse_rung(m.rung, ex.source, field + ".rung"),
                                                          m.files, m.version));
      } catch (const InputError& e) {
        throw InputError(ex.source, field, e.what());
      }
    }
    eval::Plan plan = eval::make_plan(ex, resolver);
    if (o.policy_files && !ex.backbone.starts_with("external:"))
      throw InputError(o.experiment_file, "backbone", "--policy-files needs an external:<command> backbone (got \"" +
                                                          ex.backbone + "\")");
    if (o.robot || o.policy_files)
      for (auto& pj : plan.jobs) {
        if (o.robot) pj.spec.robot = o.robot;
        if (o.policy_files) pj.spec.policy_files = o.policy_files;
        pj.job_id = eval::job_id(pj.spec);
      }
    if (o.slurm) {  // the Slurm options are checked before any file is written
      if (o.max_array_size && *o.max_array_size == 0) throw InputError("", "--max-array-size", "must be at least 1");
      if (!eval::valid_slurm_time(o.time_limit))
        throw InputError("--time", o.time_limit,
                         "not a Slurm time (M, M:S, H:M:S, D-H, D-H:M, D-H:M:S or UNLIMITED, not zero)");
      if (!o.mem.empty() && !eval::valid_slurm_mem(o.mem))
        throw InputError("--mem", o.mem, "not a Slurm memory size (a positive integer with an optional K, M, G or T)");
      if (o.cpus_per_task == 0) throw InputError("--cpus-per-task", "0", "must be at least 1");
      if (o.cpus_per_task > 4096) throw InputError("--cpus-per-task", std::to_string(o.cpus_per_task), "must be at most 4096");
      // the partition is written into the scripts: a newline or shell character there would be a command
      const bool partition_ok =
          o.partition.size() <= 256 && std::all_of(o.partition.begin(), o.partition.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == ',';
          });
      if (!partition_ok)
        throw InputError("--partition", o.partition, "not a Slurm partition list (letters, digits, _ - . and commas)");
    }
    const std::string executable = o.slurm ? resolve_executable(o.executable) : std::string();
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
      so.plan_path = fs::absolute(plan_path).lexically_normal().string();
      so.out_dir = fs::absolute(o.out_dir).lexically_normal().string();
      so.executable = executable;
      so.cpus_per_task = o.cpus_per_task;
      so.time_limit = o.time_limit;
      so.mem = o.mem;
      so.partition = o.partition;
      so.max_parallel = o.max_parallel;
      so.max_array_size = o.max_array_size ? *o.max_array_size : cluster_max_array_size();
      const std::string script_path =
          o.slurm_file.empty() ? (fs::path(o.out_dir) / (ex.name + ".sbatch")).string() : o.slurm_file;
      so.script_path = fs::absolute(script_path).lexically_normal().string();
      std::string stem = so.script_path;
      if (fs::path(stem).extension() == ".sbatch") stem = stem.substr(0, stem.size() - 7);
      so.merge_script_path = stem + ".merge.sbatch";
      const std::string submit_path = stem + ".submit.sh";
      ensure_parent(script_path);
      const auto write_script = [](const std::string& path, const std::string& text) {
        write_file_atomic(path, text);
        std::error_code pe;
        fs::permissions(path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, pe);
      };
      write_script(so.script_path, eval::slurm_array_script(plan, so));
      write_script(so.merge_script_path, eval::slurm_merge_script(plan, so));
      write_script(submit_path, eval::slurm_submit_script(plan, so));
      const auto chunks = eval::slurm_chunks(static_cast<std::int64_t>(plan.jobs.size()), so.max_array_size);
      out << "slurm array script: " << so.script_path << " (" << chunks.size()
          << (chunks.size() == 1 ? " array" : " arrays") << " under MaxArraySize " << so.max_array_size << ")\n"
          << "slurm merge script: " << so.merge_script_path << " (summarize, gates; after every array task succeeded)\n"
          << "submit everything:  bash " << submit_path << "\n";
    }
    return kOk;
  });
}

namespace {
// External policies and methods cannot see the results directory (other episodes' seeds and
// contracts), the plan and the seed file (the job's seed), nor the runner's /proc entries. The
// directory is made now, so that it exists to be hidden when the first process starts.
void configure_external_sandbox(const RunPlanOptions& o) {
  policy::SandboxConfig config;
  try {
    config.mode = policy::parse_sandbox_mode(o.sandbox);
  } catch (const std::invalid_argument& e) {
    throw InputError("command line", "--sandbox", e.what());
  }
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec) throw InputError(o.out_dir, "--out", "cannot create directory: " + ec.message());
  config.hidden_paths = o.hidden_paths;
  config.hidden_paths.push_back(o.out_dir);
  if (!o.plan_file.empty()) config.hidden_paths.push_back(o.plan_file);
  policy::configure_sandbox(std::move(config));
}
}  // namespace

int run_plan_jobs(const RunPlanOptions& o, const EpisodeFnFactory& make, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    check_output_dir(o.out_dir, "--out");
    configure_external_sandbox(o);
    const eval::Plan plan = eval::load_plan(o.plan_file);
    // a failing job is named by its plan entry (announce's line is not printed with --progress off)
    const auto run_entry = [&](const eval::PlannedJob& pj) {
      const std::string field = "jobs[" + std::to_string(pj.index) + "] (" + pj.job_id.substr(0, 12) + ")";
      try {
        run_with(pj.spec, o, make, out, err);
      } catch (const eval::Interrupted&) {
        throw;
      } catch (const std::invalid_argument& e) {
        throw InputError(o.plan_file, field, e.what());
      } catch (const std::runtime_error& e) {
        throw std::runtime_error(o.plan_file + ": " + field + ": " + e.what());
      }
    };
    if (o.job_index) {
      if (*o.job_index < 0 || *o.job_index >= static_cast<std::int64_t>(plan.jobs.size()))
        throw InputError(o.plan_file, "--job-index",
                         "out of range (plan has " + std::to_string(plan.jobs.size()) + " jobs, got " +
                             std::to_string(*o.job_index) + ")");
      const auto& pj = plan.jobs[static_cast<std::size_t>(*o.job_index)];
      announce(pj, plan.jobs.size(), o, err);
      run_entry(pj);
      return kOk;
    }
    for (const auto& pj : plan.jobs) {
      announce(pj, plan.jobs.size(), o, err);
      run_entry(pj);
    }
    return kOk;
  });
}

int run_one_job(const eval::JobSpec& job, const RunPlanOptions& o, const EpisodeFnFactory& make, std::ostream& out,
                std::ostream& err) {
  return guarded(err, [&] {
    check_output_dir(o.out_dir, "--out");
    configure_external_sandbox(o);
    run_with(job, o, make, out, err);
    return kOk;
  });
}

}  // namespace actionshift::cli
