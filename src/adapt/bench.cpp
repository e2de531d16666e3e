#include "actionshift/adapt/bench.hpp"

#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/rng.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace actionshift::adapt {

namespace {

using Clock = std::chrono::steady_clock;

double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Mat3 random_turn(Rng& rng, double max_angle) {
  const Vec3 axis = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
  return Eigen::AngleAxisd(rng.uniform(0.0, max_angle), axis).toRotationMatrix();
}

}  // namespace

nlohmann::json AdapterBenchResult::to_json() const {
  return {{"method", method},
          {"params", params},
          {"hypotheses", hypotheses},
          {"first_select_us", first_select_us},
          {"probe_encode_us", probe_encode_us},
          {"act_encode_us", act_encode_us},
          {"observe_us", observe_us},
          {"step_us", step_us},
          {"probes_per_episode", probes_per_episode}};
}

AdapterBenchResult bench_adapter(const AdapterBenchConfig& cfg) {
  const nlohmann::json params = resolve_method_params(cfg.method, cfg.params);
  if (method_needs_pool(cfg.method) && cfg.pool.empty()) throw InputError("method", cfg.method, "needs a pool (--pool)");
  if (cfg.episodes < 1) throw InputError("bench adapt", "episodes", "must be at least 1");
  if (cfg.steps < 1) throw InputError("bench adapt", "steps", "must be at least 1");
  if (cfg.repetitions < 1) throw InputError("bench adapt", "repetitions", "must be at least 1");
  cfg.model.validate();
  // truths: pool members (the identity for pool-free methods)
  const std::vector<Contract> truths = cfg.pool.empty() ? std::vector<Contract>{Contract::identity()} : cfg.pool;
  std::vector<double> first, probe, act, obs, step;
  double probes_total = 0;
  Rng rng(cfg.seed);
  for (int rep = 0; rep < cfg.repetitions; ++rep) {
    double t_first = 0, t_probe = 0, t_act = 0, t_obs = 0;
    long n_probe = 0, n_act = 0, n_steps = 0;
    for (int ep = 0; ep < cfg.episodes; ++ep) {
      const Contract& truth = truths[static_cast<std::size_t>(rng.uniform_int(truths.size()))];
      MethodInputs in;
      in.truth = &truth;
      if (!cfg.pool.empty()) in.pool = &cfg.pool;
      in.model = &cfg.model;
      auto adapter = make_adapter(cfg.method, params, in);
      Decoder env(truth);
      Mat3 R = random_turn(rng, 3.0);
      const double phase = rng.uniform(0.0, 6.3);
      adapter->begin_episode(rng.next_u64());
      for (int k = 0; k < cfg.steps; ++k) {
        Action intent;
        for (int c = 0; c < kActionDim; ++c) intent[c] = 0.9 * std::sin(0.7 * k + c + phase);
        auto t0 = Clock::now();
        const Action raw = adapter->encode(intent, R);
        const double t_enc = us_since(t0);
        if (k == 0) t_first += t_enc;
        if (adapter->last_step().probe) {
          t_probe += t_enc;
          ++n_probe;
        } else {
          t_act += t_enc;
          ++n_act;
        }
        Pose6 response = cfg.model.expected(env.step(raw, R));
        for (int c = 0; c < kPoseDim; ++c) response[c] += cfg.model.sigma[static_cast<std::size_t>(c)] * rng.normal();
        t0 = Clock::now();
        adapter->observe(raw, response, R);
        t_obs += us_since(t0);
        ++n_steps;
        R = random_turn(rng, 0.1) * R;
      }
    }
    first.push_back(t_first / cfg.episodes);
    probe.push_back(n_probe ? t_probe / static_cast<double>(n_probe) : 0.0);
    act.push_back(n_act ? t_act / static_cast<double>(n_act) : 0.0);
    obs.push_back(t_obs / static_cast<double>(n_steps));
    step.push_back((t_probe + t_act + t_obs) / static_cast<double>(n_steps));
    probes_total += static_cast<double>(n_probe);
  }
  AdapterBenchResult r;
  r.method = cfg.method;
  r.params = params;
  r.hypotheses = static_cast<int>(cfg.pool.size());
  r.first_select_us = median(first);
  r.probe_encode_us = median(probe);
  r.act_encode_us = median(act);
  r.observe_us = median(obs);
  r.step_us = median(step);
  r.probes_per_episode = probes_total / static_cast<double>(cfg.repetitions * cfg.episodes);
  return r;
}

}  // namespace actionshift::adapt
