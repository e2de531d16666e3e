// The Slurm scripts of a plan: array, merge and submit scripts; Slurm option checks
#include "actionshift/eval/slurm.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace actionshift::eval {

std::string shell_quote(std::string_view s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "'\\''";
    else out.push_back(c);
  }
  out += "'";
  return out;
}

namespace {

void require_slurm_plan(const Plan& plan, const SlurmOptions& o, const char* what) {
  if (plan.jobs.empty()) throw std::invalid_argument(std::string(what) + ": the plan has no jobs");
  if (o.plan_path.empty()) throw std::invalid_argument(std::string(what) + ": plan_path is required");
  if (o.max_array_size == 0) throw std::invalid_argument(std::string(what) + ": max_array_size must be positive");
  // #SBATCH lines are read by Slurm, not the shell: quoting cannot protect them, so a line break (or any
  // control character) in a value written there would start a line of its own, run as a shell command
  const auto one_line = [](const std::string& v, const char* field) {
    for (char c : v)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
        throw InputError("plan --slurm", field, "contains a control character (got " + quote_input(v) + "); it would break the #SBATCH lines");
  };
  one_line(o.out_dir, "--out");
  one_line(o.executable, "executable");
  one_line(o.plan_path, "plan path");
  one_line(o.time_limit, "--time");
  one_line(o.mem, "--mem");
  one_line(o.partition, "--partition");
  one_line(plan.experiment, "experiment name");
}

// The #SBATCH lines every script shares: time, memory, partition.
void common_directives(std::ostream& s, const SlurmOptions& o) {
  s << "#SBATCH --time=" << o.time_limit << "\n";
  if (!o.mem.empty()) s << "#SBATCH --mem=" << o.mem << "\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
}

bool all_digits(std::string_view t) {
  return !t.empty() && std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

std::vector<SlurmChunk> slurm_chunks(std::int64_t job_count, unsigned max_array_size) {
  if (max_array_size == 0) throw std::invalid_argument("slurm_chunks: max_array_size must be positive");
  std::vector<SlurmChunk> out;
  for (std::int64_t off = 0; off < job_count; off += max_array_size)
    out.push_back({off, std::min<std::int64_t>(max_array_size, job_count - off)});
  return out;
}

std::string slurm_array_script(const Plan& plan, const SlurmOptions& o) {
  require_slurm_plan(plan, o, "slurm_array_script");
  const unsigned cpus = o.cpus_per_task ? o.cpus_per_task : 1;
  const auto n = static_cast<std::int64_t>(plan.jobs.size());
  const auto chunks = slurm_chunks(n, o.max_array_size);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Slurm array task for experiment '" << plan.experiment << "' (" << n << " jobs in " << chunks.size()
    << (chunks.size() == 1 ? " array" : " arrays") << " of at most " << o.max_array_size << " tasks).\n"
    << "# Task i of a submission runs plan job ACTIONSHIFT_JOB_OFFSET + i (offset 0 by default).\n"
    << "# Re-submitting is safe: finished jobs are no-ops and killed or pre-empted jobs resume from\n"
    << "# their last complete record.\n";
  s << "# Submit every array and the merge job with the <experiment>.submit.sh script beside this one.\n";
  s << "#SBATCH --job-name=actionshift-" << plan.experiment << "\n";
  if (chunks.size() == 1) {
    s << "#SBATCH --array=0-" << n - 1;
    if (o.max_parallel) s << "%" << o.max_parallel;
    s << "\n";
  }
  s << "#SBATCH --cpus-per-task=" << cpus << "\n";
  common_directives(s, o);
  s << "#SBATCH --output=" << o.out_dir << "/slurm-%A_%a.log\n"
    << "#SBATCH --requeue\n"
    << "set -euo pipefail\n"
    << "job_index=$(( ${ACTIONSHIFT_JOB_OFFSET:-0} + ${SLURM_ARRAY_TASK_ID:?not a Slurm array task} ))\n"
    << "exec " << shell_quote(o.executable) << " run --plan " << shell_quote(o.plan_path)
    << " --job-index \"${job_index}\" --out " << shell_quote(o.out_dir) << " --threads \"${SLURM_CPUS_PER_TASK:-" << cpus
    << "}\"\n";
  return s.str();
}

std::string slurm_merge_script(const Plan& plan, const SlurmOptions& o) {
  require_slurm_plan(plan, o, "slurm_merge_script");
  bool oracle = false, no_adapt = false;
  for (const auto& j : plan.jobs) {
    oracle = oracle || j.spec.method == "oracle";
    no_adapt = no_adapt || j.spec.method == "no_adapt";
  }
  const std::string out = shell_quote(o.out_dir);
  const std::string exe = shell_quote(o.executable);
  const std::string base = o.out_dir + "/" + plan.experiment;
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Merge job for experiment '" << plan.experiment << "': runs after every array task succeeded\n"
    << "# (--dependency=afterok). Writes " << plan.experiment << ".summary.md and " << plan.experiment
    << ".summary.json beside the results";
  if (oracle && no_adapt) s << " and the Gate 1 verdict (exit 1 if a gated cell fails)";
  s << ".\n"
    << "#SBATCH --job-name=actionshift-" << plan.experiment << "-merge\n"
    << "#SBATCH --cpus-per-task=1\n";
  common_directives(s, o);
  s << "#SBATCH --output=" << o.out_dir << "/slurm-merge-%j.log\n"
    << "set -euo pipefail\n"
    << exe << " summarize " << out << " --out " << shell_quote(base + ".summary.json") << " > "
    << shell_quote(base + ".summary.md") << "\n";
  if (oracle && no_adapt)
    s << exe << " gate1 --results " << out << " --verdict " << shell_quote(o.out_dir + "/gate1.verdict.json") << "\n";
  return s.str();
}

std::string slurm_submit_script(const Plan& plan, const SlurmOptions& o) {
  require_slurm_plan(plan, o, "slurm_submit_script");
  if (o.script_path.empty() || o.merge_script_path.empty())
    throw std::invalid_argument("slurm_submit_script: script_path and merge_script_path are required");
  const auto chunks = slurm_chunks(static_cast<std::int64_t>(plan.jobs.size()), o.max_array_size);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Submits experiment '" << plan.experiment << "': " << plan.jobs.size() << " jobs as " << chunks.size()
    << (chunks.size() == 1 ? " array" : " arrays") << " (MaxArraySize " << o.max_array_size
    << "), then the merge job once all of them succeeded.\n"
    << "# Run from any directory: bash <this file>. Prints the Slurm job ids.\n"
    << "set -euo pipefail\n"
    << "ids=()\n";
  for (const auto& c : chunks) {
    s << "ids+=(\"$(sbatch --parsable --array=0-" << c.count - 1;
    if (o.max_parallel) s << "%" << o.max_parallel;
    s << " --export=ALL,ACTIONSHIFT_JOB_OFFSET=" << c.offset << " " << shell_quote(o.script_path)
      << " | cut -d ';' -f 1)\")\n";
  }
  s << "dep=$(IFS=:; echo \"${ids[*]}\")\n"
    << "merge=$(sbatch --parsable --dependency=afterok:\"${dep}\" --kill-on-invalid-dep=yes "
    << shell_quote(o.merge_script_path) << " | cut -d ';' -f 1)\n"
    << "echo \"array jobs: ${ids[*]}\"\n"
    << "echo \"merge job: ${merge}\"\n";
  return s.str();
}

bool valid_slurm_time(std::string_view t) {
  if (t == "UNLIMITED" || t == "INFINITE" || t == "unlimited" || t == "infinite") return true;
  std::string_view days, rest = t;
  if (const auto dash = t.find('-'); dash != std::string_view::npos) {
    days = t.substr(0, dash);
    rest = t.substr(dash + 1);
    if (!all_digits(days)) return false;
  }
  std::vector<std::string_view> parts;
  std::size_t pos = 0;
  while (true) {
    const auto colon = rest.find(':', pos);
    parts.push_back(rest.substr(pos, colon == std::string_view::npos ? std::string_view::npos : colon - pos));
    if (colon == std::string_view::npos) break;
    pos = colon + 1;
  }
  if (parts.size() > 3) return false;
  // without days: M, M:S, H:M:S; with days: D-H, D-H:M, D-H:M:S
  bool nonzero = false;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (!all_digits(parts[i]) || parts[i].size() > 9) return false;
    const long v = std::stol(std::string(parts[i]));
    nonzero = nonzero || v > 0;
    const bool leading = i == 0;  // the leading field (minutes, hours or days-hours) may exceed 59
    if (!leading && v > 59) return false;
  }
  if (!days.empty()) {
    if (days.size() > 6) return false;
    nonzero = nonzero || std::stol(std::string(days)) > 0;
    if (std::stol(std::string(parts[0])) > 23) return false;
  }
  return nonzero;
}

bool valid_slurm_mem(std::string_view t) {
  if (t.empty()) return false;
  std::string_view digits = t;
  const char last = t.back();
  if (last == 'K' || last == 'M' || last == 'G' || last == 'T' || last == 'k' || last == 'm' || last == 'g' || last == 't')
    digits = t.substr(0, t.size() - 1);
  if (!all_digits(digits) || digits.size() > 12) return false;
  return std::stoll(std::string(digits)) > 0;
}

std::optional<unsigned> parse_max_array_size(std::string_view text) {
  std::size_t pos = 0;
  while (pos < text.size()) {
    auto eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    if (line.rfind("MaxArraySize", 0) != 0) continue;
    const auto eq = line.find('=');
    if (eq == std::string_view::npos) continue;
    std::string_view v = line.substr(eq + 1);
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    while (!v.empty() && (v.back() == ' ' || v.back() == '\r' || v.back() == '\t')) v.remove_suffix(1);
    if (!all_digits(v) || v.size() > 9) return std::nullopt;
    const unsigned long n = std::stoul(std::string(v));
    if (n == 0) return std::nullopt;
    return static_cast<unsigned>(n);
  }
  return std::nullopt;
}


}  // namespace actionshift::eval
