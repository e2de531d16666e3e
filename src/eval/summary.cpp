#include "actionshift/eval/summary.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/store.hpp"
#include "io.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

namespace actionshift::eval {

namespace {
using nlohmann::json;

}  // namespace

std::string fixed(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

ResultSet load_results(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, "", "not a results directory");
  ResultSet out;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_regular_file() && entry.path().extension() == ".jsonl") out.files.push_back(entry.path().string());
  if (ec) throw InputError(dir, "", "cannot list directory: " + ec.message());
  std::sort(out.files.begin(), out.files.end());
  // Jobs that differ only in their episode count (a grown job and the job it grew from) overlap:
  // their shared episodes are counted once. The family comes from each job's summary file.
  struct Seen {
    std::size_t record;
    std::string file;
  };
  std::map<std::pair<std::string, std::int64_t>, Seen> seen;  // (family, episode index) → first record
  std::set<std::pair<std::string, std::string>> overlapping;   // (kept file, skipped file)
  std::map<std::pair<std::string, std::int64_t>, std::string> where;  // (job id, episode index) → file
  for (const auto& f : out.files) {
    RecordFile rf = read_record_file(f, /*allow_torn_tail=*/true);
    if (rf.torn_tail) out.notes.push_back(f + ": ignored an unterminated last line (job running or killed)");
    std::string family;
    const fs::path summary = fs::path(f).replace_extension(".summary.json");
    if (fs::exists(summary, ec)) {
      try {
        // a FIFO or device named like a summary must not block or stream: read_file refuses it
        const JobSpec job = job_from_json(parse_json_input(detail::read_file(summary.string(), "a job summary", kMaxJsonDocumentBytes), summary.string()).at("job"),
                                          summary.string());
        if (job_id(job) == fs::path(f).stem().string()) family = family_key(job);
      } catch (const std::exception&) {
        family.clear();  // no usable summary: the job's records stand alone
      }
    }
    for (auto& r : rf.records) {
      // the same record in two files (a copied .jsonl) would be counted twice by every consumer
      if (const auto [it, fresh] = where.emplace(std::make_pair(r.job_id, r.episode_index), f); !fresh)
        throw InputError(dir, fs::path(f).filename().string(),
                         "episode " + std::to_string(r.episode_index) + " of job " + r.job_id.substr(0, 12) + " is also in " +
                             fs::path(it->second).filename().string() + " (a copy?); keep one file per job");
      if (!family.empty()) {
        const auto [it, inserted] = seen.emplace(std::make_pair(family, r.episode_index), Seen{out.records.size(), f});
        if (!inserted) {
          EpisodeRecord a = out.records[it->second.record], b = r;
          a.job_id = b.job_id;
          a.actionshift_version = b.actionshift_version;
          a.git_commit = b.git_commit;
          if (!(a == b))
            throw InputError(dir, fs::path(f).filename().string(),
                             "overlaps " + fs::path(it->second.file).filename().string() +
                                 " (the same job with another episode count) but episode " +
                                 std::to_string(r.episode_index) + " differs between them (built from other code?); remove one");
          overlapping.emplace(it->second.file, f);
          continue;
        }
      }
      out.records.push_back(std::move(r));
    }
  }
  for (const auto& [kept, skipped] : overlapping)
    out.notes.push_back(skipped + ": the same job as " + fs::path(kept).filename().string() +
                        " with another episode count; shared episodes counted once (remove the smaller job to silence this)");
  return out;
}

CellKey cell_key(const EpisodeRecord& r) { return CellKey{r.task, r.split, r.method_variant, r.backbone}; }

std::vector<CellSummary> summarize_records(const std::vector<EpisodeRecord>& records) {
  struct Acc {
    std::int64_t n{0}, once{0}, at_end{0}, steps{0}, probe_steps{0}, flagged{0};
    double ret{0.0}, disp{0.0};
    std::map<std::uint64_t, std::pair<std::int64_t, std::int64_t>> seeds;
    std::map<std::string, std::int64_t> flags;
    std::set<std::string> jobs;
    std::map<PairKey, std::string> keys;  // key → job id, for duplicate detection
  };
  std::map<CellKey, Acc> cells;
  for (const auto& r : records) {
    Acc& a = cells[cell_key(r)];
    const PairKey k{r.seed, r.contract_index, r.episode_index};
    const auto [it, inserted] = a.keys.emplace(k, r.job_id);
    if (!inserted)
      throw InputError("results", r.task + "/" + r.split + "/" + r.method_variant,
                       "episode (seed " + std::to_string(k.seed) + ", contract " + std::to_string(k.contract_index) +
                           ", episode " + std::to_string(k.episode_index) + ") appears in jobs " +
                           it->second.substr(0, 12) + " and " + r.job_id.substr(0, 12) +
                           "; keep one job per cell and seed in a results directory");
    ++a.n;
    a.once += r.success_once;
    a.at_end += r.success_at_end;
    a.steps += r.steps;
    a.probe_steps += r.probe_steps;
    a.ret += r.task_return;
    a.disp += r.probe_displacement;
    if (!r.safety_flags.empty()) ++a.flagged;
    for (const auto& f : r.safety_flags) ++a.flags[f];
    auto& s = a.seeds[r.seed];
    ++s.first;
    s.second += r.success_once;
    a.jobs.insert(r.job_id);
  }
  std::vector<CellSummary> out;
  for (const auto& [key, a] : cells) {
    CellSummary c;
    c.key = key;
    c.episodes = a.n;
    const double n = static_cast<double>(a.n);
    c.success_once = wilson_interval(a.once, a.n);
    c.success_at_end_rate = static_cast<double>(a.at_end) / n;
    c.mean_return = a.ret / n;
    c.mean_steps = static_cast<double>(a.steps) / n;
    c.mean_probe_steps = static_cast<double>(a.probe_steps) / n;
    c.mean_probe_displacement = a.disp / n;
    for (const auto& [seed, s] : a.seeds)
      c.per_seed.push_back({seed, s.first, s.second, static_cast<double>(s.second) / static_cast<double>(s.first)});
    c.episodes_with_safety_flags = a.flagged;
    c.safety_flags = a.flags;
    c.jobs.assign(a.jobs.begin(), a.jobs.end());
    out.push_back(std::move(c));
  }
  return out;
}

nlohmann::json summary_to_json(const std::vector<CellSummary>& cells) {
  json j = {{"schema_version", "1.0"}, {"cells", json::array()}};
  for (const auto& c : cells) {
    json seeds = json::array();
    for (const auto& s : c.per_seed)
      seeds.push_back({{"seed", s.seed}, {"episodes", s.episodes}, {"successes", s.successes}, {"rate", s.rate}});
    j["cells"].push_back({{"task", c.key.task},
                          {"split", c.key.split},
                          {"method", c.key.method},
                          {"backbone", c.key.backbone},
                          {"episodes", c.episodes},
                          {"success_once", wilson_json(c.success_once)},
                          {"success_at_end_rate", c.success_at_end_rate},
                          {"mean_return", c.mean_return},
                          {"mean_steps", c.mean_steps},
                          {"mean_probe_steps", c.mean_probe_steps},
                          {"mean_probe_displacement", c.mean_probe_displacement},
                          {"per_seed", seeds},
                          {"episodes_with_safety_flags", c.episodes_with_safety_flags},
                          {"safety_flags", c.safety_flags},
                          {"jobs", c.jobs}});
  }
  return j;
}

std::string summary_to_markdown(const std::vector<CellSummary>& cells) {
  std::ostringstream s;
  s << "| task | split | method | backbone | n | success_once | Wilson 95 % | per seed | probe steps | probe disp. [m] | safety flags |\n"
    << "|---|---|---|---|---:|---:|---|---|---:|---:|---|\n";
  for (const auto& c : cells) {
    std::string seeds, flags;
    for (const auto& sr : c.per_seed) seeds += (seeds.empty() ? "" : ", ") + std::to_string(sr.seed) + ": " + fixed(sr.rate, 3);
    for (const auto& [name, count] : c.safety_flags) flags += (flags.empty() ? "" : ", ") + name + " " + std::to_string(count);
    s << "| " << c.key.task << " | " << c.key.split << " | " << c.key.method << " | " << c.key.backbone << " | "
      << c.episodes << " | " << fixed(c.success_once.rate, 3) << " | [" << fixed(c.success_once.lower, 3) << ", "
      << fixed(c.success_once.upper, 3) << "] | " << seeds << " | " << fixed(c.mean_probe_steps, 2) << " | "
      << fixed(c.mean_probe_displacement, 4) << " | " << (flags.empty() ? "—" : flags) << " |\n";
  }
  return s.str();
}

std::string no_records_reason(const ResultSet& results) {
  if (results.files.empty()) return "holds no episode records (no *.jsonl file)";
  const std::size_t n = results.files.size();
  return "holds no episode records: " + std::string(n == 1 ? "its .jsonl file is" : "its " + std::to_string(n) + " .jsonl files are") +
         " empty (a job that stopped before its first episode says why in its .summary.json)";
}

}  // namespace actionshift::eval
