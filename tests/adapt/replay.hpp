#pragma once
// Recorded probe-selection episodes (tests/adapt/data/probe_replay.json): the probe every
// selection chose, the task regret DualABI computed and the belief after every step, recorded by
// actionshift_probe_replay_record (replay_record.cpp) and replayed by replay_test.cpp, so any
// rewrite of the selection code can be checked against the decisions of the code that made the
// recording.
//
// An episode is synthetic but exercises every path of the real selection: a built-in pool
// (reference9 or full), the method's registry defaults (what `actionshift run` uses), a response
// model, a true contract from the pool with its own decoder, a slowly turning TCP orientation R
// (tool-frame contracts depend on it) and the response α ⊙ executed + Gaussian noise.
#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/data/builtin_manifests.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace actionshift::testing {

struct ReplaySpec {
  std::string method;   // entropy_probes | dualabi
  nlohmann::json params;  // overrides of the registry defaults
  std::string pool;     // built-in pool name
  adapt::ResponseModel model;
  int truth_index{0};   // into the pool
  std::uint64_t seed{0};
  int steps{8};
};

inline nlohmann::json to_json(const Action& a) { return std::vector<double>(a.data(), a.data() + a.size()); }
inline nlohmann::json to_json(const Pose6& a) { return std::vector<double>(a.data(), a.data() + a.size()); }

template <class V>
V vec_from_json(const nlohmann::json& j) {
  V v;
  if (!j.is_array() || j.size() != static_cast<std::size_t>(v.size())) throw std::runtime_error("replay fixture: bad vector " + j.dump());
  for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = j[static_cast<std::size_t>(i)].get<double>();
  return v;
}

inline Action replay_intent(int k) {
  Action a;
  for (int c = 0; c < kActionDim; ++c) a[c] = 0.9 * std::sin(0.7 * k + c);
  return a;
}

/// Runs one episode with the current code and returns its record.
inline nlohmann::json record_episode(const ReplaySpec& s) {
  const std::vector<Contract> pool = data::resolve_manifest(s.pool).contracts();
  const nlohmann::json params = adapt::resolve_method_params(s.method, s.params);
  adapt::MethodInputs in;
  in.pool = &pool;
  in.model = &s.model;
  auto adapter = adapt::make_adapter(s.method, params, in);
  const Contract& truth = pool.at(static_cast<std::size_t>(s.truth_index));
  Decoder env(truth);
  Rng rng(s.seed);
  Mat3 R = Eigen::AngleAxisd(rng.uniform(0.0, 3.0), Vec3(rng.normal(), rng.normal(), rng.normal()).normalized()).toRotationMatrix();
  adapter->begin_episode(s.seed);
  nlohmann::json steps = nlohmann::json::array();
  for (int k = 0; k < s.steps; ++k) {
    const Action a = replay_intent(k);
    const Action raw = adapter->encode(a, R);
    const adapt::StepInfo info = adapter->last_step();
    Pose6 response = s.model.expected(env.step(raw, R));
    for (int c = 0; c < kPoseDim; ++c) response[c] += s.model.sigma[static_cast<std::size_t>(c)] * rng.normal();
    adapter->observe(raw, response, R);
    const auto* belief_of = [&]() -> const adapt::PoolBelief* {
      if (auto* p = dynamic_cast<const adapt::ProbingAdapter*>(adapter.get())) return &p->belief();
      if (auto* d = dynamic_cast<const adapt::DualAbiAdapter*>(adapter.get())) return &d->belief();
      return nullptr;
    }();
    if (!belief_of) throw std::runtime_error("replay: method " + s.method + " has no pool belief");
    const Eigen::VectorXd& logp = belief_of->log_probs();
    if (!logp.allFinite()) throw std::runtime_error("replay: non-finite log belief");
    nlohmann::json st;
    st["intent"] = to_json(a);
    st["R"] = std::vector<double>{R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)};
    st["raw"] = to_json(raw);
    st["probe"] = info.probe;
    st["task_regret"] = info.task_regret;
    st["response"] = to_json(response);
    st["logp"] = std::vector<double>(logp.data(), logp.data() + logp.size());
    steps.push_back(st);
    // the TCP turns a little each step (a random axis, up to 0.1 rad)
    R = Eigen::AngleAxisd(rng.uniform(0.0, 0.1), Vec3(rng.normal(), rng.normal(), rng.normal()).normalized()).toRotationMatrix() * R;
  }
  nlohmann::json ep;
  ep["method"] = s.method;
  ep["params"] = params;
  ep["pool"] = s.pool;
  ep["alpha"] = s.model.alpha;
  ep["sigma"] = s.model.sigma;
  ep["truth_index"] = s.truth_index;
  ep["seed"] = s.seed;
  ep["steps"] = steps;
  return ep;
}

}  // namespace actionshift::testing
