// The seed registry (configs/seeds.yaml, docs/formats.md "Seed registry") against the tree.
//
// Anything chosen by looking at outcomes is chosen on pilot seeds and episodes that no evaluation uses.
// check_seed_registry(registry, experiments dir, scripts dir) checks it: every experiment (recursively)
// and every seed literal a script passes is registered with its file and a consistent role; no seed is
// both a selection seed (pilot, adoption) and an evaluation seed (evaluation, selftest); and no initial
// state of a pilot or adoption run is one of an evaluation's. The same function runs on the real tree
// (no problem) and on tests/eval/data/seed_overlap/ (a deliberately overlapping tree: it must fail).
#include "actionshift/core/manifest.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/experiment_yaml.hpp"
#include "actionshift/eval/identifier_train.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/eval/statistics.hpp"
#include "actionshift/policy/gate0.hpp"
#include "actionshift/policy/ppo.hpp"
#include "actionshift/policy/dp.hpp"
#include "actionshift/policy/train.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace actionshift::eval {
namespace {

namespace fs = std::filesystem;

const fs::path kSource = fs::path(ACTIONSHIFT_SOURCE_DIR);
const fs::path kFixture = kSource / "tests" / "eval" / "data" / "seed_overlap";

// Episodes per job whose initial states are compared (every committed experiment has at most 256).
constexpr std::int64_t kMaxEpisodesPerJob = 4096;

const std::set<std::string> kRoles = {"evaluation", "pilot",     "adoption", "training", "generation",
                                      "calibration", "bootstrap", "selftest", "timing",   "auxiliary"};
const std::set<std::string> kSelectionRoles = {"pilot", "adoption"};
const std::set<std::string> kEvaluationRoles = {"evaluation", "selftest"};

struct EpisodeBlock {
  std::string runner;               // "job" or "gate0"
  std::vector<std::string> splits;  // job: every split
  std::int64_t episodes{0};         // job: per_job; gate0: count
};

struct Use {
  std::string path;  // relative to the repository root, generic form
  std::string role;
  std::string at;
  bool implicit{false};
  std::vector<EpisodeBlock> episodes;
};

struct Entry {
  std::uint64_t seed{0};
  std::set<std::string> roles;
  std::vector<Use> uses;
};

using Registry = std::map<std::uint64_t, Entry>;

std::string str(std::uint64_t s) { return std::to_string(s); }

std::string join(const std::set<std::string>& s) {
  std::string out;
  for (const auto& x : s) out += (out.empty() ? "" : ", ") + x;
  return out;
}

// The repository root of a registry: <root>/configs/seeds.yaml.
fs::path root_of(const fs::path& registry) { return registry.parent_path().parent_path(); }

std::string rel(const fs::path& p, const fs::path& root) { return fs::relative(p, root).generic_string(); }

bool has_use(const Entry& e, const std::string& path, const std::string& role = "") {
  return std::any_of(e.uses.begin(), e.uses.end(),
                     [&](const Use& u) { return u.path == path && (role.empty() || u.role == role); });
}

// A use of `e` names `file` itself or a directory holding it.
bool lists_file(const Entry& e, const std::string& file) {
  return std::any_of(e.uses.begin(), e.uses.end(), [&](const Use& u) {
    return u.path == file || file.rfind(u.path + "/", 0) == 0;
  });
}

std::vector<EpisodeBlock> parse_episodes(const YAML::Node& n, const std::string& where, std::vector<std::string>& problems) {
  std::vector<EpisodeBlock> out;
  std::vector<YAML::Node> items;
  if (n.IsSequence())
    for (const auto& x : n) items.push_back(x);
  else
    items.push_back(n);
  for (const auto& x : items) {
    EpisodeBlock b;
    b.runner = x["runner"] ? x["runner"].as<std::string>() : "";
    if (b.runner == "job") {
      if (x["splits"])
        for (const auto& s : x["splits"]) b.splits.push_back(s.as<std::string>());
      b.episodes = x["per_job"] ? x["per_job"].as<std::int64_t>() : 0;
      if (b.splits.empty() || b.episodes <= 0) problems.push_back(where + ": episodes: a job block needs splits and per_job > 0");
    } else if (b.runner == "gate0") {
      b.episodes = x["count"] ? x["count"].as<std::int64_t>() : 0;
      if (b.episodes <= 0) problems.push_back(where + ": episodes: a gate0 block needs count > 0");
    } else {
      problems.push_back(where + ": episodes: runner must be job or gate0, not '" + b.runner + "'");
      continue;
    }
    out.push_back(b);
  }
  return out;
}

// Reads the registry; structural problems are appended to `problems`.
Registry load_registry(const fs::path& file, std::vector<std::string>& problems) {
  Registry reg;
  const std::string name = file.generic_string();
  YAML::Node doc;
  try {
    doc = YAML::LoadFile(file.string());
  } catch (const std::exception& e) {
    problems.push_back(name + ": cannot read the registry: " + e.what());
    return reg;
  }
  if (!doc["version"] || doc["version"].as<int>() != 1) problems.push_back(name + ": version must be 1");
  if (!doc["seeds"] || !doc["seeds"].IsSequence() || doc["seeds"].size() == 0) {
    problems.push_back(name + ": seeds: a non-empty list is required");
    return reg;
  }
  const fs::path root = root_of(file);
  for (const auto& n : doc["seeds"]) try {
    Entry e;
    try {
      e.seed = n["seed"].as<std::uint64_t>();
    } catch (const std::exception&) {
      problems.push_back(name + ": an entry without an unsigned seed");
      continue;
    }
    const std::string where = name + ": seed " + str(e.seed);
    if (reg.count(e.seed)) problems.push_back(where + ": listed twice");
    if (n["roles"])
      for (const auto& r : n["roles"]) e.roles.insert(r.as<std::string>());
    for (const auto& r : e.roles)
      if (!kRoles.count(r)) problems.push_back(where + ": unknown role '" + r + "' (known: " + join(kRoles) + ")");
    if (e.roles.empty()) problems.push_back(where + ": roles: at least one");
    if (!n["uses"] || !n["uses"].IsSequence() || n["uses"].size() == 0) problems.push_back(where + ": uses: at least one");
    std::set<std::string> used_roles;
    if (n["uses"])
      for (const auto& un : n["uses"]) {
        Use u;
        u.path = un["path"] ? un["path"].as<std::string>() : "";
        u.role = un["role"] ? un["role"].as<std::string>() : "";
        u.at = un["at"] ? un["at"].as<std::string>() : "";
        u.implicit = un["implicit"] && un["implicit"].as<bool>();
        const std::string uw = where + ": use " + u.path + " (role " + u.role + ")";
        if (u.path.empty() || u.at.empty()) problems.push_back(uw + ": path and at are required");
        else if (!fs::exists(root / u.path)) problems.push_back(uw + ": no such file or directory");
        if (!e.roles.count(u.role)) problems.push_back(uw + ": role not among the entry's roles (" + join(e.roles) + ")");
        if (un["episodes"]) u.episodes = parse_episodes(un["episodes"], uw, problems);
        used_roles.insert(u.role);
        e.uses.push_back(std::move(u));
      }
    for (const auto& r : e.roles)
      if (!used_roles.count(r)) problems.push_back(where + ": role " + r + " has no use");
    reg[e.seed] = std::move(e);
  } catch (const std::exception& ex) {
    problems.push_back(name + ": a malformed entry: " + ex.what());
  }
  return reg;
}

// --------------------------------------------------------------------------- script scanning
//
// A script passes a seed when a line, with its comment removed (from a '#' at the start of the line
// or after a blank, outside quotes), matches one of:
//   --seed N, --seed=N, "--seed", "N"                               (a command line)
//   <name ending in seed/seeds> = N | "N N ..." | 'N ...' | [N, ...]  (SEEDS="...", seed=N, DESIGN_SEEDS = [...])
//   for <name containing seed> in N N ...;                          (a shell loop over literals)
//   seeds: [N, ...]                                                  (experiment YAML written by a script)
//   Random(N), default_rng(N), RandomState(N), manual_seed(N), seed(N)  (RNG seeds)
//   default=N on a line naming "--seed"                              (argparse default)
struct ScriptSeed {
  std::uint64_t seed;
  int line;
};

std::string strip_comment(const std::string& line) {
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == '\\') ++i;
      else if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
      return line.substr(0, i);
    }
  }
  return line;
}

void add_numbers(const std::string& text, int line, std::vector<ScriptSeed>& out) {
  static const std::regex num(R"(\d+)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), num); it != std::sregex_iterator(); ++it)
    out.push_back({std::stoull(it->str()), line});
}

std::vector<ScriptSeed> scan_script(const fs::path& file) {
  static const std::regex cli(R"re(--seed(?:\s+|=|["']\s*,\s*)["']?(\d+)\b)re");
  static const std::regex assign(R"re(\b[A-Za-z_]*(?:seeds?|SEEDS?)\s*=\s*(\[[^\]]*\]|"[^"]*"|'[^']*'|\d+))re");
  static const std::regex loop(R"re(\bfor\s+\w*(?:seed|SEED)\w*\s+in\s+(\d[\d\s]*);)re");
  // a shell default, SEEDS="${SEEDS:-20260718 20260719}": the seeds a script runs when the caller sets none
  static const std::regex shell_default(R"re(\$\{\w*(?:seed|SEED)\w*:-["']?(\d[\d\s]*)["']?\})re");
  static const std::regex yaml_seeds(R"re(\bseeds:\s*\[([\d,\s]+)\])re");
  static const std::regex rng(R"re(\b(?:Random|default_rng|RandomState|manual_seed|seed)\((\d+)\))re");
  static const std::regex argparse_default(R"re(default\s*=\s*(\d+))re");
  static const std::regex digits_only(R"re(^[\[\]"'\d\s,]*$)re");
  std::vector<ScriptSeed> out;
  std::ifstream in(file, std::ios::binary);
  std::string raw;
  int line_no = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    if (raw.find('\0') != std::string::npos) return {};  // not a text file
    const std::string line = strip_comment(raw);
    std::smatch m;
    for (auto it = std::sregex_iterator(line.begin(), line.end(), cli); it != std::sregex_iterator(); ++it)
      add_numbers((*it)[1].str(), line_no, out);
    for (auto it = std::sregex_iterator(line.begin(), line.end(), assign); it != std::sregex_iterator(); ++it)
      if (std::regex_match((*it)[1].str(), digits_only)) add_numbers((*it)[1].str(), line_no, out);
    for (const auto* re : {&loop, &yaml_seeds, &rng, &shell_default})
      for (auto it = std::sregex_iterator(line.begin(), line.end(), *re); it != std::sregex_iterator(); ++it)
        add_numbers((*it)[1].str(), line_no, out);
    if (line.find("--seed") != std::string::npos && std::regex_search(line, m, argparse_default))
      add_numbers(m[1].str(), line_no, out);
  }
  return out;
}

std::vector<fs::path> files_under(const fs::path& dir, const std::string& extension = "") {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file() && (extension.empty() || e.path().extension() == extension)) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// --------------------------------------------------------------------------- initial states

struct Origin {
  std::string source;  // "<file> seed S"
  std::string what;    // "split X episode i" or "gate0 episode k"
  std::string role;
};

// Environment seeds of a job's first episodes, through the runner's own episode_task.
void add_job_episodes(const std::string& split, std::uint64_t seed, std::int64_t episodes, const std::string& source,
                      const std::string& role, std::multimap<std::uint64_t, Origin>& out, std::vector<std::string>& problems) {
  static std::map<std::string, SplitRef> splits;  // resolved once per name
  JobSpec job;
  try {
    if (!splits.count(split)) {
      const Manifest m = data::resolve_manifest(split);
      splits[split] = SplitRef{m.name(), m.manifest_sha256(), static_cast<std::int64_t>(m.test().size())};
    }
    job.split = splits.at(split);
  } catch (const std::exception& e) {
    problems.push_back(source + ": split " + split + ": " + e.what());
    return;
  }
  if (job.split.contracts <= 0) {
    problems.push_back(source + ": split " + split + " has no evaluation contracts");
    return;
  }
  job.task = "pick_cube";
  job.seed = seed;
  job.episodes = episodes;
  for (std::int64_t i = 0; i < std::min(episodes, kMaxEpisodesPerJob); ++i)
    out.emplace(episode_task(job, i).episode_seed,
                Origin{source + " seed " + str(seed), "split " + split + " episode " + std::to_string(i), role});
}

// Gate 0's episodes: contract index 0, env seed derive_seed({seed, 0, k}) (policy/rollout.hpp, gate0.hpp).
void add_gate0_episodes(std::uint64_t seed, std::int64_t count, const std::string& source, const std::string& role,
                        std::multimap<std::uint64_t, Origin>& out) {
  for (std::int64_t k = 0; k < std::min(count, kMaxEpisodesPerJob); ++k)
    out.emplace(derive_seed({seed, 0, static_cast<std::uint64_t>(k)}),
                Origin{source + " seed " + str(seed), "gate0 episode " + std::to_string(k), role});
}

// --------------------------------------------------------------------------- the checker

// Every problem of the registry against the experiments and scripts, one line each naming file, seed
// and role. Empty: the registry is complete and the selection runs are disjoint from the evaluations.
std::vector<std::string> check_seed_registry(const fs::path& registry_file, const fs::path& experiments_dir,
                                             const fs::path& scripts_dir) {
  std::vector<std::string> problems;
  const Registry reg = load_registry(registry_file, problems);
  const fs::path root = root_of(registry_file);
  const std::string rname = rel(registry_file, root);

  // 1. a selection seed is never an evaluation seed
  for (const auto& [seed, e] : reg) {
    std::set<std::string> sel, ev;
    for (const auto& r : e.roles) {
      if (kSelectionRoles.count(r)) sel.insert(r);
      if (kEvaluationRoles.count(r)) ev.insert(r);
    }
    if (!sel.empty() && !ev.empty())
      problems.push_back(rname + ": seed " + str(seed) + " has both a selection role (" + join(sel) +
                         ") and an evaluation role (" + join(ev) + ")");
  }

  // env seed -> where it is used, by role
  std::multimap<std::uint64_t, Origin> episodes;

  // 2. every experiment, recursively
  int experiments = 0;
  for (const auto& path : files_under(experiments_dir, ".yaml")) {
    const std::string file = rel(path, root);
    Experiment ex;
    try {
      ex = load_experiment(path.string());
    } catch (const std::exception& e) {
      problems.push_back(file + ": cannot load the experiment: " + e.what());
      continue;
    }
    ++experiments;
    bool pilot = ex.name.find("pilot") != std::string::npos;
    for (const auto& [seed, e] : reg) pilot = pilot || has_use(e, file, "pilot");
    const std::string role = pilot ? "pilot" : "evaluation";
    const std::set<std::uint64_t> seeds(ex.seeds.begin(), ex.seeds.end());
    for (auto seed : ex.seeds) {
      const auto it = reg.find(seed);
      if (it == reg.end())
        problems.push_back(file + ": seed " + str(seed) + " (" + role + ") is not in the registry " + rname);
      else if (!has_use(it->second, file, role))
        problems.push_back(file + ": seed " + str(seed) + " (" + role + ") is not registered for this file with role " +
                           role + " in " + rname);
      for (const auto& split : ex.splits) add_job_episodes(split, seed, ex.episodes, file, role, episodes, problems);
    }
    for (const auto& [seed, e] : reg)
      for (const auto& u : e.uses)
        if (u.path == file && !u.implicit && !seeds.count(seed))
          problems.push_back(rname + ": seed " + str(seed) + " (" + u.role + ") lists " + file +
                             ", whose seeds do not include it (stale use)");
  }
  if (experiments == 0) problems.push_back(experiments_dir.generic_string() + ": no experiment found");

  // 3. every script under scripts/
  for (const auto& path : files_under(scripts_dir)) {
    const std::string file = rel(path, root);
    std::set<std::uint64_t> found;
    for (const auto& [seed, line] : scan_script(path)) {
      found.insert(seed);
      const auto it = reg.find(seed);
      const std::string where = file + ":" + std::to_string(line) + ": seed " + str(seed);
      if (it == reg.end())
        problems.push_back(where + " is not in the registry " + rname);
      else if (!has_use(it->second, file))
        problems.push_back(where + " (registered as " + join(it->second.roles) + ") does not list this file in " + rname);
    }
    for (const auto& [seed, e] : reg)
      for (const auto& u : e.uses)
        if (u.path == file && !u.implicit && !found.count(seed))
          problems.push_back(rname + ": seed " + str(seed) + " (" + u.role + ") lists " + file +
                             ", which passes no such seed (stale use; mark it implicit if it is not a literal)");
  }

  // 4. the episodes the registry declares (script runs, archived pilots, adoption pilots)
  for (const auto& [seed, e] : reg)
    for (const auto& u : e.uses)
      for (const auto& b : u.episodes) {
        if (b.runner == "job")
          for (const auto& split : b.splits) add_job_episodes(split, seed, b.episodes, u.path, u.role, episodes, problems);
        else
          add_gate0_episodes(seed, b.episodes, u.path, u.role, episodes);
      }

  // 5. no initial state of a selection run is an evaluation's: one line per (selection, evaluation) pair
  struct Shared {
    std::size_t count{0};
    std::string example;
  };
  std::map<std::pair<std::string, std::string>, Shared> shared;
  for (auto it = episodes.begin(); it != episodes.end();) {
    const auto range = episodes.equal_range(it->first);
    for (auto a = range.first; a != range.second; ++a) {
      if (!kSelectionRoles.count(a->second.role)) continue;
      for (auto b = range.first; b != range.second; ++b) {
        if (!kEvaluationRoles.count(b->second.role)) continue;
        Shared& s = shared[{a->second.source + " (" + a->second.role + ")", b->second.source + " (" + b->second.role + ")"}];
        if (s.count++ == 0)
          s.example = "env seed " + str(it->first) + ": " + a->second.what + " = " + b->second.what;
      }
    }
    it = range.second;
  }
  for (const auto& [pair, s] : shared)
    problems.push_back(pair.first + " shares " + std::to_string(s.count) + " initial state(s) with " + pair.second +
                       ", e.g. " + s.example);
  return problems;
}

std::string lines(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += "  " + s + "\n";
  return out;
}

bool any_contains(const std::vector<std::string>& v, const std::string& a, const std::string& b = "") {
  return std::any_of(v.begin(), v.end(), [&](const std::string& s) {
    return s.find(a) != std::string::npos && (b.empty() || s.find(b) != std::string::npos);
  });
}

// --------------------------------------------------------------------------- tests

TEST(SeedRegistry, RealTreeIsRegisteredAndSelectionRunsAreDisjointFromEvaluations) {
  const auto problems = check_seed_registry(kSource / "configs" / "seeds.yaml", kSource / "configs" / "experiments",
                                            kSource / "scripts");
  EXPECT_TRUE(problems.empty()) << problems.size() << " problem(s):\n" << lines(problems);
}

TEST(SeedRegistry, OverlappingFixtureFails) {
  const auto problems = check_seed_registry(kFixture / "configs" / "seeds.yaml", kFixture / "configs" / "experiments",
                                            kFixture / "scripts");
  ASSERT_FALSE(problems.empty());
  // seed 12 is the pilot's and an evaluation's: by role and by initial state
  EXPECT_TRUE(any_contains(problems, "seed 12 has both a selection role (pilot) and an evaluation role (evaluation)"))
      << lines(problems);
  EXPECT_TRUE(any_contains(problems, "configs/experiments/tau_pilot.yaml seed 12 (pilot) shares ",
                           " initial state(s) with configs/experiments/eval.yaml seed 12 (evaluation)"))
      << lines(problems);
  // the adoption pilot's Gate 0 episodes are an evaluation's Gate 0 episodes
  EXPECT_TRUE(any_contains(problems, "docs/adoption.md seed 16 (adoption) shares 5 initial state(s) with "
                                     "scripts/gate0_eval seed 16 (evaluation)"))
      << lines(problems);
  // a nested experiment's seed nobody registered
  EXPECT_TRUE(any_contains(problems, "configs/experiments/nested/late.yaml: seed 14 (evaluation) is not in the registry"))
      << lines(problems);
  // a pilot experiment registered as an evaluation only
  EXPECT_TRUE(any_contains(problems, "configs/experiments/nested/late_pilot.yaml: seed 11 (pilot) is not registered"))
      << lines(problems);
  // a script's seeds: unregistered, and registered without the script
  EXPECT_TRUE(any_contains(problems, "scripts/run_pilot:", "seed 13 is not in the registry")) << lines(problems);
  EXPECT_TRUE(any_contains(problems, "scripts/run_pilot:", "seed 11 (registered as evaluation) does not list this file"))
      << lines(problems);
  // a use the file no longer has
  EXPECT_TRUE(any_contains(problems, "seed 15 (evaluation) lists configs/experiments/eval.yaml", "stale use"))
      << lines(problems);
}

TEST(SeedRegistry, ScriptScannerFindsEachDocumentedPatternAndIgnoresComments) {
  const fs::path dir = fs::temp_directory_path() / ("seed_scan_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::create_directories(dir);
  const fs::path f = dir / "script";
  std::ofstream(f) << "#!/usr/bin/env bash\n"
                      "# --seed 900 in a comment is not a use\n"
                      "\"$AS\" run --seed 901 --episodes 5   # --seed 902\n"
                      "\"$AS\" run --seed=903\n"
                      "SEEDS=\"904 905\"\n"
                      "for seed in 906 907; do echo \"#$seed\"; done\n"
                      "sed -e 's/^seeds: .*/seeds: [908, 909]/' x\n"
                      "rng = random.Random(910); r = np.random.default_rng(911)\n"
                      "ap.add_argument(\"--seed\", type=int, default=912)\n"
                      "def f(seed=913, rng_seed=seed): pass\n"
                      "DESIGN_SEEDS = [914, 915]\n"
                      "subprocess.run([AS, \"--seed\", \"916\"])\n"
                      "seed=$4; SEEDS=\"$X\"; episodes=917; seeds_text = 918\n"
                      "SEEDS=\"${SEEDS:-919 920}\"; SEED=${SEED:-921}; EPISODES=${EPISODES:-922}\n";
  std::set<std::uint64_t> found;
  for (const auto& s : scan_script(f)) found.insert(s.seed);
  fs::remove_all(dir);
  std::set<std::uint64_t> want;
  for (std::uint64_t s = 901; s <= 921; ++s)
    if (s != 902 && s != 917 && s != 918) want.insert(s);
  EXPECT_EQ(found, want);
}

TEST(SeedRegistry, LibraryAndCliDefaultsAreRegisteredWithTheirRoles) {
  std::vector<std::string> problems;
  const Registry reg = load_registry(kSource / "configs" / "seeds.yaml", problems);
  ASSERT_TRUE(problems.empty()) << lines(problems);
  const struct {
    std::uint64_t seed;
    const char* role;
    const char* what;
  } defaults[] = {
      {JobRequest{}.seed, "evaluation", "JobRequest{}.seed (run, render, evaluate)"},
      {policy::Gate0Run{}.seed, "evaluation", "policy::Gate0Run{}.seed (gate0)"},
      {policy::TrainBcOptions{}.seed, "training", "policy::TrainBcOptions{}.seed (train bc)"},
      {policy::PpoOptions{}.seed, "training", "policy::PpoOptions{}.seed (train ppo)"},
      {policy::TrainDpOptions{}.seed, "training", "policy::TrainDpOptions{}.seed (train dp)"},
      {TrainIdentifierOptions{}.seed, "training", "TrainIdentifierOptions{}.seed (train identifier)"},
      {CalibrationOptions{}.seed, "calibration", "CalibrationOptions{}.seed (calibrate)"},
      {kBootstrapSeed, "bootstrap", "kBootstrapSeed (gate1, gate promote)"},
      {kDefaultSeed, "generation", "kDefaultSeed (splits generate)"},
  };
  for (const auto& d : defaults) {
    const auto it = reg.find(d.seed);
    ASSERT_NE(it, reg.end()) << d.what << " = " << d.seed << " is not in configs/seeds.yaml";
    EXPECT_TRUE(it->second.roles.count(d.role)) << d.what << " = " << d.seed << ": registered as "
                                                << join(it->second.roles) << ", not " << d.role;
  }
  // the command line's default seed is an evaluation seed, never a selection seed
  for (const auto& r : kSelectionRoles) EXPECT_FALSE(reg.at(JobRequest{}.seed).roles.count(r)) << r;
}

// The seeds recorded in committed files: the weights' headers (training.seed) and the manifests' generator seeds.
TEST(SeedRegistry, SeedsRecordedInCommittedFilesAreRegistered) {
  std::vector<std::string> problems;
  const Registry reg = load_registry(kSource / "configs" / "seeds.yaml", problems);
  ASSERT_TRUE(problems.empty()) << lines(problems);
  int files = 0;
  const auto expect = [&](const fs::path& p, std::uint64_t seed, const std::string& role) {
    ++files;
    const std::string file = rel(p, kSource);
    const auto it = reg.find(seed);
    if (it == reg.end()) {
      ADD_FAILURE() << file << ": recorded seed " << seed << " (" << role << ") is not in configs/seeds.yaml";
      return;
    }
    EXPECT_TRUE(it->second.roles.count(role)) << file << ": seed " << seed << " is not registered as " << role;
    EXPECT_TRUE(lists_file(it->second, file)) << file << ": seed " << seed << " (" << role << ") does not list this file";
  };
  // weight files: magic (8 bytes), uint32 version, uint32 header length, JSON header
  const auto header_seed = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    char head[16];
    in.read(head, 16);
    std::uint32_t n = 0;
    std::memcpy(&n, head + 12, 4);
    std::string json(n, '\0');
    in.read(json.data(), n);
    return nlohmann::json::parse(json).at("training").at("seed").get<std::uint64_t>();
  };
  for (const auto& p : files_under(kSource / "configs" / "backbones", ".asmlp")) expect(p, header_seed(p), "training");
  for (const auto& p : files_under(kSource / "configs" / "identifiers", ".asid")) expect(p, header_seed(p), "training");
  for (const auto& p : files_under(kSource / "manifests", ".json")) {
    std::ifstream in(p);
    expect(p, nlohmann::json::parse(in).at("seed").get<std::uint64_t>(), "generation");
  }
  for (const auto& p : files_under(kSource / "configs" / "calibration", ".json")) {
    std::ifstream in(p);
    const auto j = nlohmann::json::parse(in);
    if (j.contains("seed")) expect(p, j.at("seed").get<std::uint64_t>(), "calibration");
  }
  EXPECT_GE(files, 13 + 3 + 11);
}

}  // namespace
}  // namespace actionshift::eval
