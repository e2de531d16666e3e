#include "actionshift/sim/vec_env.hpp"

#include "actionshift/core/types.hpp"
#include "actionshift/core/workers.hpp"

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <string>

namespace actionshift::sim {

VecEnv::VecEnv(std::shared_ptr<const EnvModel> model, const std::vector<Contract>& contracts, FrameRotation rotation,
               unsigned threads)
    : model_(std::move(model)), rotation_(rotation) {
  if (contracts.empty()) throw std::invalid_argument("VecEnv: no environments (one contract per environment)");
  envs_.reserve(contracts.size());
  for (const Contract& c : contracts) envs_.emplace_back(model_, c, rotation_);
  pool_ = std::make_unique<WorkerPool>(std::min<unsigned>(resolve_threads(threads), static_cast<unsigned>(envs_.size())));
}

VecEnv::~VecEnv() = default;

unsigned VecEnv::threads() const { return pool_->size(); }

void VecEnv::set_contract(int i, const Contract& contract) {
  envs_.at(static_cast<std::size_t>(i)) = HiddenContractEnv(model_, contract, rotation_);
}

void VecEnv::for_each(const std::function<void(int)>& f) {
  // environments are handed out one at a time (a step with contact costs several times one without),
  // so a worker that drew cheap ones takes the next; results go to slots by index, never by worker
  const int n = size();
  std::atomic<int> next{0};
  pool_->run([&](unsigned) {
    for (int i = next.fetch_add(1); i < n; i = next.fetch_add(1)) f(i);
  });
}

void VecEnv::step(std::span<const double> actions, const std::function<void(int, const StepResult&)>& then) {
  const auto need = static_cast<std::size_t>(kActionDim) * envs_.size();
  if (actions.size() != need)
    throw std::invalid_argument("VecEnv::step: " + std::to_string(actions.size()) + " numbers for " +
                                std::to_string(envs_.size()) + " environments (expected " + std::to_string(need) + ")");
  for_each([&](int i) {
    const auto k = static_cast<std::size_t>(i) * kActionDim;
    then(i, envs_[static_cast<std::size_t>(i)].step(actions.subspan(k, kActionDim)));
  });
}

}  // namespace actionshift::sim
