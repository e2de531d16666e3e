#pragma once
// Synthetic record sets for summary and gate tests: n episodes per seed over 2 contracts, with the
// k-th episode's success chosen by a predicate.

#include "actionshift/core/hash.hpp"
#include "actionshift/eval/record.hpp"

#include <functional>
#include <string>
#include <vector>

namespace actionshift::eval::testing {

inline std::vector<EpisodeRecord> make_records(const std::string& task, const std::string& split, const std::string& method,
                                               std::vector<std::uint64_t> seeds, int n,
                                               const std::function<bool(int k)>& success,
                                               const std::string& backbone = "expert") {
  std::vector<EpisodeRecord> out;
  for (auto seed : seeds) {
    const std::string id = sha256_hex(task + split + method + std::to_string(seed));
    for (int k = 0; k < n; ++k) {
      EpisodeRecord r;
      r.job_id = id;
      r.task = task;
      r.split = split;
      r.method = method.substr(0, method.find('{'));  // a label's base name
      r.method_variant = method;
      r.seed = seed;
      r.contract_index = k % 2;
      r.contract_sha256 = sha256_hex(split + std::to_string(k % 2));
      r.episode_index = k;
      r.success_once = success(k);
      r.success_at_end = r.success_once;
      r.task_return = r.success_once ? 10.0 : 1.0;
      r.steps = 50;
      r.backbone = backbone;
      r.backbone_sha256 = sha256_hex(backbone);
      out.push_back(std::move(r));
    }
  }
  return out;
}

inline std::vector<EpisodeRecord> concat(std::vector<EpisodeRecord> a, const std::vector<EpisodeRecord>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace actionshift::eval::testing
