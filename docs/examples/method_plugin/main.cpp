// Registers the separation_probes plug-in and runs one job of it through the library's runner, exactly
// as `actionshift run` runs a built-in method: hash-addressed JSONL records and a summary in OUT.
//
//   separation_example OUT [EPISODES [BACKBONE [SEED [SPLIT [POOL]]]]]
//   defaults: 18 episodes, backbone expert, seed 20260718, split reference_seen, pool reference9
#include "separation_probes.hpp"

#include <actionshift/core/error.hpp>
#include <actionshift/eval/episode_fn.hpp>
#include <actionshift/eval/plan_expand.hpp>
#include <actionshift/eval/resolve.hpp>
#include <actionshift/eval/runner.hpp>

#include <iostream>
#include <string>

int main(int argc, char** argv) {
  namespace eval = actionshift::eval;
  if (argc < 2) {
    std::cerr << "usage: separation_example OUT [EPISODES [BACKBONE [SEED [SPLIT [POOL]]]]]\n";
    return 2;
  }
  try {
    // the registration lasts as long as `method`: register before resolving or running its jobs
    const auto method = actionshift::adapt::register_method(separation::plugin());
    eval::JobRequest q;
    q.task = "pick_cube";
    q.method.name = "separation_probes";
    q.episodes = argc > 2 ? std::stoll(argv[2]) : 18;
    q.backbone = argc > 3 ? argv[3] : "expert";
    q.seed = argc > 4 ? std::stoull(argv[4]) : 20260718;
    q.split = argc > 5 ? argv[5] : "reference_seen";
    q.pool = argc > 6 ? argv[6] : "reference9";
    q.source = "separation_example";
    const eval::JobSpec job = eval::resolve_job(q, eval::default_resolver());
    eval::RunOptions options;
    options.out_dir = argv[1];
    options.progress = eval::ProgressMode::off;
    const eval::RunResult r = eval::run_job(job, eval::make_episode_fn(job), options);
    std::cout << r.job_id << " " << r.jsonl_path << "\n";
    return 0;
  } catch (const actionshift::InputError& e) {
    std::cerr << "separation_example: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "separation_example: " << e.what() << "\n";
    return 1;
  }
}
