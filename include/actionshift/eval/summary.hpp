#pragma once
/// \file Merging results: every `*.jsonl` of a directory into per-(task, split, method, backbone)
/// cells with success rates, Wilson intervals, probe costs, per-seed rates and safety-flag counts.

#include "actionshift/eval/record.hpp"
#include "actionshift/eval/statistics.hpp"

#include <nlohmann/json_fwd.hpp>

#include <compare>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace actionshift::eval {

/// All records of a results directory.
struct ResultSet {
  std::vector<EpisodeRecord> records;   ///< every record, files in name order, lines in file order
  std::vector<std::string> files;       ///< the `*.jsonl` files read
  std::vector<std::string> notes;       ///< one line per file whose torn last line was ignored
};

/// Read every `*.jsonl` in `dir` (not recursive). An unterminated last line (a job still running or
/// killed) is ignored and noted. Throws actionshift::InputError if `dir` is not a directory or a line
/// is invalid (naming `<file>:<line>`).
ResultSet load_results(const std::string& dir);

/// Why `results` (read from `dir`) holds no records, as one line for an error: no `*.jsonl` at all,
/// or only empty ones (jobs that stopped before their first episode; their summaries say why).
std::string no_records_reason(const ResultSet& results);

/// Identity of an episode for pairing across methods: same seed, contract and episode index means
/// the same initial state.
struct PairKey {
  std::uint64_t seed{0};
  std::int64_t contract_index{0};
  std::int64_t episode_index{0};
  auto operator<=>(const PairKey&) const = default;
};

/// A summary cell.
struct CellKey {
  std::string task, split, method, backbone;
  auto operator<=>(const CellKey&) const = default;
};

/// The cell of a record: (task, split, method variant label, backbone). Two variants of one method
/// (`entropy_probes`, `entropy_probes{calibrated}`) are two cells.
CellKey cell_key(const EpisodeRecord& r);

/// Success of one seed within a cell.
struct SeedRate {
  std::uint64_t seed{0};
  std::int64_t episodes{0};
  std::int64_t successes{0};   ///< success_once count
  double rate{0.0};            ///< successes / episodes
};

/// Aggregates of one cell.
struct CellSummary {
  CellKey key;
  std::int64_t episodes{0};                 ///< n
  WilsonInterval success_once;              ///< success_once with its Wilson 95 % interval
  double success_at_end_rate{0.0};          ///< fraction with success_at_end
  double mean_return{0.0};                  ///< mean episode return
  double mean_steps{0.0};                   ///< mean control steps
  double mean_probe_steps{0.0};             ///< mean probe steps per episode
  double mean_probe_displacement{0.0};      ///< [m] mean probe displacement per episode
  std::vector<SeedRate> per_seed;           ///< ascending seed
  std::int64_t episodes_with_safety_flags{0};   ///< episodes with ≥ 1 flag
  std::map<std::string, std::int64_t> safety_flags;  ///< count per flag name
  std::vector<std::string> jobs;            ///< job ids contributing, sorted
};

/// Group records into cells (sorted by key). Throws actionshift::InputError if a pairing key occurs
/// twice in one cell (two jobs of the same cell and seed in one directory).
std::vector<CellSummary> summarize_records(const std::vector<EpisodeRecord>& records);

/// {"schema_version":"1.0","cells":[...]} (docs/formats.md "Results summary").
nlohmann::json summary_to_json(const std::vector<CellSummary>& cells);

/// A Markdown table, one row per cell.
std::string summary_to_markdown(const std::vector<CellSummary>& cells);

/// Fixed-point formatting used in tables and reason strings (like Python's `{:.Nf}`).
std::string fixed(double x, int digits);

}  // namespace actionshift::eval
