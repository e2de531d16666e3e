// `actionshift compare`: the comparison JSON of one or more results directories (eval/compare.hpp).
#include "cmd_eval.hpp"
#include "commands.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/eval/compare.hpp"
#include "actionshift/eval/store.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>

namespace actionshift::cli {

int run_compare(const CompareOptions& o) {
  try {
    if (!o.out_file.empty()) {
      check_output_file(o.out_file, "--out");
      require_replaceable_output(o.out_file);
    }
    std::vector<eval::ComparisonPair> pairs;
    for (const auto& text : o.pairs) pairs.push_back(eval::parse_comparison_pair(text, "--pair", ""));
    if (!o.pairs_file.empty()) {
      const auto more = eval::parse_pairs_text(read_input_file(o.pairs_file, "a pairs file", std::uintmax_t{1} << 20), o.pairs_file);
      if (more.empty()) throw InputError(o.pairs_file, "", "holds no pair (one 'CANDIDATE vs BASELINE' per line)");
      pairs.insert(pairs.end(), more.begin(), more.end());
    }
    const eval::PaperNumbers paper =
        o.paper_file.empty() ? eval::builtin_paper_numbers()
                             : eval::parse_paper_numbers(read_input_file(o.paper_file, "a paper-numbers file", std::uintmax_t{64} << 20),
                                                         o.paper_file);
    const nlohmann::json j = eval::compare_directories(o.results_dirs, pairs, paper, o.common_episodes, o.across_backbones);
    for (const auto& d : j["inputs"]["results_dirs"])
      for (const auto& note : d["notes"]) std::cerr << "actionshift: note: " << note.get<std::string>() << "\n";
    if (o.out_file.empty()) {
      std::cout << j.dump(2) << "\n";
    } else {
      const std::filesystem::path parent = std::filesystem::path(o.out_file).parent_path();
      std::error_code ec;
      if (!parent.empty()) std::filesystem::create_directories(parent, ec);
      if (ec) throw InputError(parent.string(), "", "cannot create directory: " + ec.message());
      eval::write_json_atomic(o.out_file, j);
    }
    return kOk;
  } catch (const std::invalid_argument& e) {  // InputError derives from it
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

}  // namespace actionshift::cli
