// Replays the recorded probe-selection episodes (tests/adapt/data/probe_replay.json, see
// replay.hpp): every probe the current code chooses must be the recorded one, every other action
// and DualABI's task regret must agree within 1e-12, and the belief after every step within 1e-12.
#include "replay.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace actionshift::adapt {
namespace {

nlohmann::json load_fixture() {
  const std::string path = std::string(ACTIONSHIFT_SOURCE_DIR) + "/tests/adapt/data/probe_replay.json";
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open " + path);
  std::stringstream ss;
  ss << f.rdbuf();
  return nlohmann::json::parse(ss.str());
}

const PoolBelief& belief_of(const Adapter& a) {
  if (auto* p = dynamic_cast<const ProbingAdapter*>(&a)) return p->belief();
  return dynamic_cast<const DualAbiAdapter&>(a).belief();
}

bool near(double a, double b, double tol = 1e-12) { return std::abs(a - b) <= tol * std::max(1.0, std::abs(b)); }

TEST(ProbeReplay, EveryRecordedDecisionAndPosteriorIsReproduced) {
  const nlohmann::json fx = load_fixture();
  ASSERT_EQ(fx.at("schema"), "actionshift-probe-replay/1");
  std::map<std::string, int> episodes, probes;  // per method/pool: coverage of the fixture itself
  std::map<std::string, std::vector<Contract>> pools;
  for (const auto& ep : fx.at("episodes")) {
    const std::string method = ep.at("method"), pool_name = ep.at("pool");
    const std::string key = method + "/" + pool_name;
    SCOPED_TRACE(key + " truth " + std::to_string(ep.at("truth_index").get<int>()));
    if (!pools.count(pool_name)) pools[pool_name] = data::resolve_manifest(pool_name).contracts();
    const auto& pool = pools[pool_name];
    const ResponseModel model{ep.at("alpha").get<std::array<double, kPoseDim>>(), ep.at("sigma").get<std::array<double, kPoseDim>>()};
    MethodInputs in;
    in.pool = &pool;
    in.model = &model;
    auto adapter = make_adapter(method, resolve_method_params(method, ep.at("params")), in);
    adapter->begin_episode(ep.at("seed").get<std::uint64_t>());
    ++episodes[key];
    int k = 0;
    for (const auto& st : ep.at("steps")) {
      SCOPED_TRACE("step " + std::to_string(k++));
      const Action intent = testing::vec_from_json<Action>(st.at("intent"));
      const auto& r = st.at("R");
      Mat3 R;
      for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = r.at(static_cast<std::size_t>(i)).get<double>();
      const Action want_raw = testing::vec_from_json<Action>(st.at("raw"));
      const Action raw = adapter->encode(intent, R);
      const StepInfo info = adapter->last_step();
      ASSERT_EQ(info.probe, st.at("probe").get<bool>());
      if (info.probe) {
        ++probes[key];
        ASSERT_EQ(raw, want_raw) << "chosen probe " << raw.transpose() << " recorded " << want_raw.transpose();
      } else {
        for (int c = 0; c < kActionDim; ++c) ASSERT_TRUE(near(raw[c], want_raw[c])) << c << ": " << raw[c] << " vs " << want_raw[c];
      }
      EXPECT_TRUE(near(info.task_regret, st.at("task_regret").get<double>()))
          << info.task_regret << " vs " << st.at("task_regret").get<double>();
      // the recorded response was caused by the recorded raw action
      adapter->observe(want_raw, testing::vec_from_json<Pose6>(st.at("response")), R);
      const Eigen::VectorXd& logp = belief_of(*adapter).log_probs();
      const auto& want = st.at("logp");
      ASSERT_EQ(static_cast<std::size_t>(logp.size()), want.size());
      for (Eigen::Index h = 0; h < logp.size(); ++h) {
        const double w = want[static_cast<std::size_t>(h)].get<double>();
        ASSERT_TRUE(near(logp[h], w)) << "hypothesis " << h << ": log p " << logp[h] << " vs " << w;
        ASSERT_LE(std::abs(std::exp(logp[h]) - std::exp(w)), 1e-12) << "hypothesis " << h;
      }
    }
  }
  // the fixture covers both methods on both pools, with selections (not only stops) in each
  for (const char* key : {"entropy_probes/reference9", "entropy_probes/full", "dualabi/reference9", "dualabi/full"}) {
    EXPECT_GE(episodes[key], 3) << key;
    EXPECT_GE(probes[key], 6) << key;
  }
}

}  // namespace
}  // namespace actionshift::adapt
