#pragma once
// A synthetic robot for adapter tests: the true contract's decoder, then response = α ⊙ canonical
// + Gaussian noise. Intents follow 0.9·sin(k + c) as in the reference's tests.
#include "actionshift/adapt/adapter.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/rng.hpp"

#include <cmath>

namespace actionshift::testing {

inline adapt::ResponseModel pick_like() {
  return {{0.032, 0.016, 0.018, -0.035, -0.027, -0.038}, {0.03, 0.02, 0.02, 0.04, 0.05, 0.04}};
}

inline Action intent(int k) {
  Action a;
  for (int c = 0; c < 7; ++c) a[c] = 0.9 * std::sin(k + c);
  return a;
}

struct SyntheticRun {
  int steps_to_identify{-1};     // first step after which the MAP is the truth for good (-1: never)
  double final_intent_error{0};  // ‖executed − intended‖ at the last step
  int probe_steps{0};
};

/// Runs `adapter` for `steps` steps against `truth` and reports when its belief's MAP settles.
template <class A>
SyntheticRun run_synthetic(A& adapter, const Contract& truth, const adapt::ResponseModel& model, int steps,
                           std::uint64_t seed, double noise_scale = 1.0) {
  Decoder env(truth);
  Rng rng(seed);
  adapter.begin_episode(seed);
  SyntheticRun out;
  const Mat3 R = Mat3::Identity();
  for (int k = 0; k < steps; ++k) {
    const Action a = intent(k);
    const Action raw = adapter.encode(a, R);
    out.probe_steps += adapter.last_step().probe ? 1 : 0;
    const Action exec = env.step(raw, R);
    Pose6 resp = model.expected(exec);
    for (int c = 0; c < 6; ++c) resp[c] += noise_scale * model.sigma[static_cast<std::size_t>(c)] * rng.normal();
    adapter.observe(raw, resp, R);
    const bool right = adapter.belief().pool()[static_cast<std::size_t>(adapter.belief().map_index())] == truth;
    if (right && out.steps_to_identify < 0) out.steps_to_identify = k + 1;
    if (!right) out.steps_to_identify = -1;
    if (k == steps - 1 && !adapter.last_step().probe) out.final_intent_error = (exec - a).head<6>().norm();
  }
  return out;
}

}  // namespace actionshift::testing
