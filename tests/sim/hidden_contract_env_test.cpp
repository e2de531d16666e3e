// hidden-contract wrapper: no contract on the agent side, oracle precision, fail-closed raw actions
#include "actionshift/sim/hidden_contract_env.hpp"

#include "actionshift/core/manifest.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/core/rng.hpp"
#include "oracle_access.hpp"  // src/eval: the runner's factory of the oracle view

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace actionshift::sim {
namespace {

using reference::oracle_contract;
using reference::representative_contracts;
using reference::with;

// ---- compile-time: the agent-facing type offers no path to the contract
template <class T, class = void>
struct has_contract : std::false_type {};
template <class T>
struct has_contract<T, std::void_t<decltype(std::declval<const T&>().contract())>> : std::true_type {};
template <class T, class = void>
struct has_decoder : std::false_type {};
template <class T>
struct has_decoder<T, std::void_t<decltype(std::declval<const T&>().decoder())>> : std::true_type {};
template <class T, class = void>
struct has_oracle : std::false_type {};
template <class T>
struct has_oracle<T, std::void_t<decltype(std::declval<const T&>().oracle())>> : std::true_type {};
template <class T, class = void>
struct has_env : std::false_type {};
template <class T>
struct has_env<T, std::void_t<decltype(std::declval<const T&>().env())>> : std::true_type {};
template <class T, class = void>
struct has_contract_json : std::false_type {};
template <class T>
struct has_contract_json<T, std::void_t<decltype(std::declval<const T&>().contract_json())>> : std::true_type {};

static_assert(!has_contract<HiddenContractEnv>::value, "the agent side must not reach the contract");
static_assert(!has_decoder<HiddenContractEnv>::value, "the agent side must not reach the decoder");
static_assert(!has_oracle<HiddenContractEnv>::value, "the agent side must not reach the oracle");
static_assert(!has_env<HiddenContractEnv>::value, "the agent side must not reach the unwrapped env");
static_assert(!has_contract_json<HiddenContractEnv>::value, "the agent side must not reach the contract");
static_assert(!std::is_copy_constructible_v<HiddenContractEnv>);
// the idiom does detect the accessor where it exists
static_assert(has_contract<OracleRecorder>::value && has_contract_json<OracleRecorder>::value);
// only the runner's factory can construct the oracle's view (oracle_view_negative.cpp proves the
// same by failing to compile)
static_assert(!std::is_constructible_v<OracleRecorder, const HiddenContractEnv&>);
static_assert(!std::is_default_constructible_v<OracleRecorder::Key>);

TEST(HiddenContractEnv, PublicInterfaceIsObservationsInRawActionsOut) {
  static_assert(std::is_same_v<decltype(std::declval<HiddenContractEnv&>().reset(std::uint64_t{})), const Eigen::VectorXd&>);
  static_assert(std::is_same_v<decltype(std::declval<HiddenContractEnv&>().step(std::span<const double>{})), const StepResult&>);
  static_assert(std::is_same_v<decltype(std::declval<HiddenContractEnv&>().step(Action{})), const StepResult&>);
  static_assert(std::is_same_v<decltype(std::declval<const HiddenContractEnv&>().layout()), const ObservationLayout&>);
  HiddenContractEnv env(EnvModel::make(TaskId::kPullCube), oracle_contract());
  EXPECT_EQ(env.task(), TaskId::kPullCube);
  EXPECT_EQ(env.horizon(), 50);
  EXPECT_EQ(env.reset(1).size(), env.layout().size());
}

std::vector<Contract> reference_manifest_contracts() {
  std::vector<Contract> out;
  for (const char* name : {"reference_seen", "reference_unseen_composition", "reference_long_lag"}) {
    const std::string path = std::string(ACTIONSHIFT_SOURCE_DIR) + "/manifests/" + name + ".json";
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    const Manifest m = Manifest::parse(ss.str(), path);
    for (const auto& r : m.test()) out.push_back(r.contract);
  }
  return out;
}

TEST(HiddenContractEnv, OracleEncodeThenWrapperDecodeReproducesTheCanonicalAction) {
  const std::vector<Contract> contracts = reference_manifest_contracts();
  ASSERT_EQ(contracts.size(), 6u);
  const auto model = EnvModel::make(TaskId::kPickCube);
  for (FrameRotation rot : {FrameRotation::kLive, FrameRotation::kIdentity}) {
    for (std::size_t ci = 0; ci < contracts.size(); ++ci) {
      HiddenContractEnv env(model, contracts[ci], rot);
      const OracleRecorder oracle = eval::detail::OracleAccess::view(env);
      EXPECT_EQ(oracle.contract_json(), contracts[ci].to_json());
      env.reset(100 + ci);
      Rng rng(ci);
      std::vector<Action> wanted;
      double worst = 0.0;
      const int lag = contracts[ci].lag();
      for (int t = 0; t < 50; ++t) {
        Action c;
        for (int k = 0; k < 6; ++k) c(k) = rng.uniform(-0.4, 0.4);
        c(6) = rng.coin() ? 1.0 : -1.0;
        wanted.push_back(c);
        const Action raw = oracle.encode(c);
        const StepResult& r = env.step(raw);
        ASSERT_EQ(r.safety, SafetyFlag::kNone) << "contract " << ci << " step " << t;
        ASSERT_EQ(oracle.decoded().size(), static_cast<std::size_t>(t + 1));
        worst = std::max(worst, (oracle.decoded().back() - c).cwiseAbs().maxCoeff());
        const Action expect_applied = t >= lag ? wanted[static_cast<std::size_t>(t - lag)] : Action::Zero();
        worst = std::max(worst, (oracle.applied().back() - expect_applied).cwiseAbs().maxCoeff());
      }
      EXPECT_LT(worst, 1e-9) << "contract " << contracts[ci].sha256() << " rotation " << static_cast<int>(rot);
      EXPECT_EQ(env.episode().steps, 50);
    }
  }
}

TEST(HiddenContractEnv, IdentityContractMatchesTheUnwrappedEnvByteForByte) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  HiddenContractEnv wrapped(model, Contract::identity());
  Env plain(model);
  const Eigen::VectorXd a0 = wrapped.reset(8), b0 = plain.reset(8);
  EXPECT_EQ(std::memcmp(a0.data(), b0.data(), sizeof(double) * static_cast<std::size_t>(a0.size())), 0);
  Rng rng(5);
  for (int t = 0; t < 20; ++t) {
    Action c;
    for (int k = 0; k < 7; ++k) c(k) = rng.uniform(-0.5, 0.5);
    const Eigen::VectorXd a = wrapped.step(c).obs, b = plain.step(c).obs;
    ASSERT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())), 0) << "step " << t;
  }
}

TEST(HiddenContractEnv, ToolFrameUsesTheLiveTcpOrientationUnlessIdentityMode) {
  const Contract tool = with(Contract::identity(), "delta", "tool", 0);
  const auto model = EnvModel::make(TaskId::kPickCube);
  HiddenContractEnv live(model, tool, FrameRotation::kLive), flat(model, tool, FrameRotation::kIdentity);
  live.reset(2);
  flat.reset(2);
  const OracleRecorder ol = eval::detail::OracleAccess::view(live), of = eval::detail::OracleAccess::view(flat);
  const Mat3 r = ol.frame_rotation();
  EXPECT_NEAR(r.col(2).z(), -1.0, 0.05);  // hand points down at rest
  EXPECT_TRUE(of.frame_rotation().isIdentity());
  Action raw = Action::Zero();
  raw(0) = 0.5;  // +x of the tool frame
  live.step(raw);
  flat.step(raw);
  EXPECT_TRUE(ol.decoded().back().head<3>().isApprox(r.col(0) * 0.5, 1e-12));
  EXPECT_TRUE(of.decoded().back().head<3>().isApprox(Eigen::Vector3d(0.5, 0, 0), 1e-12));
}

TEST(HiddenContractEnv, SteppingOrReadingStateBeforeTheFirstResetThrowsInsteadOfCrashing) {
  // the Bullet world holds a robot only after a reset: these used to dereference a null robot
  const auto model = EnvModel::make(TaskId::kPushCube);
  HiddenContractEnv env(model, Contract::identity());
  EXPECT_THROW(env.step(Action::Zero()), std::logic_error);
  Env raw(model);
  EXPECT_THROW(raw.step(Action::Zero()), std::logic_error);
  EXPECT_THROW(raw.qpos(), std::logic_error);
  EXPECT_THROW(raw.tcp_pose(), std::logic_error);
  EXPECT_THROW(raw.tcp_pose_in_base(), std::logic_error);
  EXPECT_THROW(raw.snapshot(), std::logic_error);
  EXPECT_THROW(raw.finger_forces(), std::logic_error);
  // after a reset all of them work
  env.reset(3);
  EXPECT_EQ(env.step(Action::Zero()).safety, SafetyFlag::kNone);
  raw.reset(3);
  EXPECT_NO_THROW(raw.snapshot());
  EXPECT_NO_THROW(raw.finger_forces());
  EXPECT_TRUE(raw.tcp_pose().matrix().allFinite());
}

TEST(HiddenContractEnv, RawNanSixElementAndHugeActionsEndTheEpisodeWithAFlag) {
  const auto model = EnvModel::make(TaskId::kPickCube);
  for (const Contract& c : representative_contracts("unseen_composition")) {
    HiddenContractEnv env(model, c);
    const OracleRecorder oracle = eval::detail::OracleAccess::view(env);
    auto run = [&](std::vector<double> raw) {
      env.reset(6);
      env.step(oracle.encode(Action::Zero()));
      return env.step(std::span<const double>(raw)).safety;
    };
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(run({nan, 0, 0, 0, 0, 0, 0}), SafetyFlag::kNonfiniteAction);
    EXPECT_EQ(run({0, 0, 0, 0, 0, 0}), SafetyFlag::kBadActionShape);
    EXPECT_EQ(run({}), SafetyFlag::kBadActionShape);
    EXPECT_EQ(run({0, 0, 0, 1e9, 0, 0, 0}), SafetyFlag::kActionOutOfRange);
    EXPECT_EQ(oracle.decoded().size(), 1u) << "a rejected raw action never reaches the decoder";
    EXPECT_TRUE(env.last().obs.allFinite());
    EXPECT_EQ(safety_flag_name(env.episode().safety), "action_out_of_range");
    // the process and the next episode carry on
    env.reset(7);
    EXPECT_EQ(env.step(oracle.encode(Action::Zero())).safety, SafetyFlag::kNone);
  }
  // an in-range raw action whose decode leaves the sane range (absolute target far away) is flagged too
  EnvConfig cfg;
  cfg.max_action_magnitude = 10.0;
  HiddenContractEnv env(EnvModel::make(TaskId::kPickCube, cfg), with(Contract::identity(), "absolute", "base", 0));
  env.reset(1);
  Action raw = Action::Zero();
  raw(0) = 9.0;
  EXPECT_EQ(env.step(raw).safety, SafetyFlag::kNone);  // canonical 9: clipped to 1 and counted
  raw(0) = -9.0;
  EXPECT_EQ(env.step(raw).safety, SafetyFlag::kActionOutOfRange);  // canonical -18
}

}  // namespace
}  // namespace actionshift::sim
