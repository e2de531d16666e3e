#pragma once
/// \file The project's one vectorised environment: several hidden-contract environments stepped together
/// on one persistent worker pool. PPO's rollouts (policy/ppo.cpp) and the Python module's `make_vec` both
/// run on it. Each environment keeps its own Bullet world, episode and seed; step() runs environment i
/// with row i of the actions and then `then(i, result)` on the same worker, so per-environment work (an
/// automatic reset, copying a row out) runs in parallel too. Write results by environment index, never
/// by worker: the outcome then does not depend on the number of threads (docs/sim.md §9).

#include "actionshift/core/contract.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"

#include <functional>
#include <memory>
#include <span>
#include <vector>

namespace actionshift {
class WorkerPool;  // the project's worker pool (not installed; pool() is for the library's own loops)
}  // namespace actionshift

namespace actionshift::sim {

class VecEnv {
 public:
  /// One environment per contract, all on `model`; `threads` workers (0: all cores), at most one per
  /// environment. Throws std::invalid_argument for no contracts.
  VecEnv(std::shared_ptr<const EnvModel> model, const std::vector<Contract>& contracts,
         FrameRotation rotation = FrameRotation::kLive, unsigned threads = 0);
  ~VecEnv();
  VecEnv(const VecEnv&) = delete;
  VecEnv& operator=(const VecEnv&) = delete;

  int size() const { return static_cast<int>(envs_.size()); }
  unsigned threads() const;
  HiddenContractEnv& env(int i) { return envs_.at(static_cast<std::size_t>(i)); }
  const HiddenContractEnv& env(int i) const { return envs_.at(static_cast<std::size_t>(i)); }
  /// Environment i runs `contract` from its next reset on (a fresh world: PPO's delay-aware rollouts
  /// draw a lag for every episode). Call it from f(i) of for_each/step, or between calls.
  void set_contract(int i, const Contract& contract);

  /// f(i) once for every environment i, on the workers; waits, and rethrows the first exception.
  void for_each(const std::function<void(int)>& f);
  /// Environment i steps with actions[7i, 7i + 7) and then(i, its result) runs on the same worker;
  /// waits, and rethrows the first exception. actions must hold 7 x size() numbers.
  void step(std::span<const double> actions, const std::function<void(int, const StepResult&)>& then);

  /// The pool the environments step on, for other parallel work of the same loop (PPO's gradient chunks).
  WorkerPool& pool() { return *pool_; }

 private:
  std::shared_ptr<const EnvModel> model_;
  FrameRotation rotation_;
  std::vector<HiddenContractEnv> envs_;
  std::unique_ptr<WorkerPool> pool_;
};

}  // namespace actionshift::sim
