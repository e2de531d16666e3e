#pragma once
// A deterministic stand-in for the simulator: outcomes are pure functions of the episode seed, so
// runs can be compared byte for byte. Shared by the eval tests and the fake-job helper executable.

#include "actionshift/core/hash.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/runner.hpp"

#include <chrono>
#include <string>
#include <thread>

namespace actionshift::eval::testing {

inline JobSpec fake_job(std::int64_t episodes, std::string method = "oracle", std::uint64_t seed = 20260718) {
  JobSpec j;
  j.task = "pick_cube";
  j.split = {"seen", sha256_hex("seen-manifest"), 3};
  j.method = std::move(method);
  j.backbone = {"expert", sha256_hex("expert-backbone")};
  j.seed = seed;
  j.episodes = episodes;
  return j;
}

inline std::string fake_contract_sha(std::int64_t contract_index) {
  return sha256_hex("contract-" + std::to_string(contract_index));
}

// success with probability ~success_percent/100, a float return, probe counts and a rare safety flag
inline EpisodeFn fake_episode_fn(int success_percent = 70, int sleep_ms = 0) {
  return [=](const EpisodeTask& t) {
    if (sleep_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms));
    const std::uint64_t h = t.episode_seed;
    EpisodeRecord r;
    r.contract_sha256 = fake_contract_sha(t.contract_index);
    r.success_once = static_cast<int>(h % 100) < success_percent;
    r.success_at_end = r.success_once && (h >> 8) % 4 != 0;
    r.task_return = static_cast<double>((h >> 16) % 100000) / 1000.0 - 12.5;
    r.steps = 50;
    r.probe_steps = static_cast<std::int64_t>((h >> 32) % 7);
    r.probe_displacement = static_cast<double>((h >> 40) % 1000) * 1e-4;
    if ((h >> 20) % 23 == 0) r.safety_flags = {"workspace_violation"};
    return r;
  };
}

}  // namespace actionshift::eval::testing
