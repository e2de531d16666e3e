// episode loops and the parallel episode runner (one Env and one policy clone per thread)
#include "actionshift/policy/rollout.hpp"

#include "actionshift/core/workers.hpp"

#include "actionshift/core/rng.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>

namespace actionshift::policy {
namespace {

template <class EnvT>
EpisodeOutcome run_loop(EnvT& env, Policy& policy, std::uint64_t env_seed, bool stop_on_success) {
  policy.reset();
  Eigen::VectorXd obs = env.reset(env_seed);
  EpisodeOutcome out;
  out.env_seed = env_seed;
  while (true) {
    const Action a = policy.act(obs);
    const sim::StepResult& r = env.step(a);
    obs = r.obs;
    if (r.episode_over() || (stop_on_success && r.success)) break;
  }
  const sim::EpisodeStats& s = env.episode();
  out.success_once = s.success_once;
  out.success_at_end = s.success_at_end;
  out.episode_return = s.episode_return;
  out.steps = s.steps;
  out.safety = s.safety;
  return out;
}

}  // namespace

EpisodeOutcome run_episode(sim::Env& env, Policy& policy, std::uint64_t env_seed, bool stop_on_success) {
  return run_loop(env, policy, env_seed, stop_on_success);
}

EpisodeOutcome run_episode(sim::HiddenContractEnv& env, Policy& policy, std::uint64_t env_seed, bool stop_on_success) {
  return run_loop(env, policy, env_seed, stop_on_success);
}

unsigned resolve_threads(unsigned requested) { return actionshift::resolve_threads(requested); }

std::vector<EpisodeOutcome> run_episodes(const Policy& policy, std::shared_ptr<const sim::EnvModel> model,
                                         const RolloutOptions& o) {
  const std::int64_t n = std::max<std::int64_t>(o.episodes, 0);
  std::vector<EpisodeOutcome> results(static_cast<std::size_t>(n));
  const unsigned threads = static_cast<unsigned>(std::min<std::int64_t>(resolve_threads(o.threads), std::max<std::int64_t>(n, 1)));
  std::atomic<std::int64_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex mu;
  std::int64_t finished = 0;
  // each worker takes the next episode index; results land in their own slot
  auto worker = [&] {
    try {
      std::unique_ptr<Policy> p = policy.clone();
      std::optional<sim::Env> env;
      std::optional<sim::HiddenContractEnv> wrapped;
      if (o.contract) wrapped.emplace(model, *o.contract);
      else env.emplace(model);
      while (!failed.load()) {
        const std::int64_t k = next.fetch_add(1);
        if (k >= n) break;
        const std::uint64_t seed = derive_seed({o.seed, o.contract_index, static_cast<std::uint64_t>(k)});
        EpisodeOutcome r = wrapped ? run_episode(*wrapped, *p, seed, o.stop_on_success)
                                   : run_episode(*env, *p, seed, o.stop_on_success);
        r.episode_index = k;
        results[static_cast<std::size_t>(k)] = r;
        std::lock_guard<std::mutex> lock(mu);
        ++finished;
        if (o.progress) o.progress(finished, n);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu);
      if (!error) error = std::current_exception();
      failed.store(true);
    }
  };
  run_workers(threads, [&](unsigned) { worker(); });
  if (error) std::rethrow_exception(error);
  return results;
}

}  // namespace actionshift::policy
