// external-process policy: the Python example completes episodes; dead, silent and garbage
// processes give clear errors instead of hangs or crashes; clones start no more processes than needed
#include "actionshift/core/hash.hpp"
#include "actionshift/policy/external.hpp"
#include "actionshift/policy/gate0.hpp"
#include "actionshift/policy/registry.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <thread>

using namespace actionshift;
using ::testing::HasSubstr;

namespace {

const std::string kReady = R"(read l; echo '{"type":"ready"}'; )";

template <class F>
void expect_runtime_error(F f, const std::string& part) {
  EXPECT_THAT(f, ::testing::ThrowsMessage<std::runtime_error>(HasSubstr(part)));
}

Eigen::VectorXd pick_obs() { return Eigen::VectorXd::Zero(sim::observation_layout(sim::TaskId::kPickCube).size()); }

#ifdef ACTIONSHIFT_PYTHON
TEST(ExternalPolicy, PythonExampleSolvesPickCube) {
  const std::string cmd = std::string(ACTIONSHIFT_PYTHON) + " " ACTIONSHIFT_SOURCE_DIR "/docs/examples/external_policy.py";
  auto p = policy::make_policy("external:" + cmd, sim::TaskId::kPickCube);
  EXPECT_EQ(p->name(), "external:" + cmd);
  policy::Gate0Run run;
  run.episodes = 6;
  run.threads = 2;
  const auto v = policy::run_gate0(*p, run);
  EXPECT_GE(v.competence.interval.successes, 5);
  EXPECT_EQ(v.decision, "advance");
}
#endif

TEST(ExternalPolicy, ProcessThatDiesIsAnError) {
  expect_runtime_error([] { policy::ExternalPolicy("exit 3", sim::TaskId::kPickCube); }, "process exited with status 3");
  policy::ExternalPolicy p(kReady + "read l; read l; exit 4", sim::TaskId::kPickCube);
  p.reset();
  expect_runtime_error([&] { p.act(pick_obs()); }, "step 0: process exited with status 4 before replying");
}

TEST(ExternalPolicy, GarbageRepliesAreErrors) {
  policy::ExternalPolicy p(kReady + "read l; read l; echo 'hello there'; read l; echo '{\"action\":[1,2]}'; sleep 5",
                           sim::TaskId::kPickCube);
  p.reset();
  expect_runtime_error([&] { p.act(pick_obs()); }, "step 0: bad reply (not JSON): 'hello there'");
  expect_runtime_error([&] { p.act(pick_obs()); }, "action must be an array of 7 numbers");
  expect_runtime_error([] { policy::ExternalPolicy("read l; echo '{}'; sleep 5", sim::TaskId::kPickCube); },
                       "hello: expected {\"type\":\"ready\"}");
}

TEST(ExternalPolicy, SilentProcessTimesOut) {
  policy::ExternalOptions o;
  o.step_timeout_s = 0.3;
  policy::ExternalPolicy p(kReady + "sleep 30", sim::TaskId::kPickCube, o);
  p.reset();
  expect_runtime_error([&] { p.act(pick_obs()); }, "no reply within 0.300 s (timeout)");
}

// SIGINT/SIGTERM handlers call interrupt_external_policies(): a policy blocked in a step is not
// waited for (it was, for the whole step timeout), and its process group is killed at once
TEST(ExternalPolicy, InterruptStopsABlockedStepAtOnceAndKillsTheGroup) {
  policy::ExternalOptions o;
  o.step_timeout_s = 30.0;
  const std::string pid_file = ::testing::TempDir() + "external_interrupt_" + std::to_string(getpid()) + ".pid";
  auto p = std::make_unique<policy::ExternalPolicy>(kReady + "sleep 1000 & echo $! > " + pid_file + "; read l; read l; wait",
                                                    sim::TaskId::kPickCube, o);
  p->reset();
  std::thread signal([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    policy::interrupt_external_policies();
  });
  const auto t0 = std::chrono::steady_clock::now();
  expect_runtime_error([&] { p->act(pick_obs()); }, "step 0: interrupted (SIGINT or SIGTERM)");
  signal.join();
  const auto seconds_since = [](auto t) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count(); };
  EXPECT_LT(seconds_since(t0), 2.0) << "a blocked step must not wait for the 30 s step timeout";
  pid_t child = -1;
  std::ifstream(pid_file) >> child;
  ASSERT_GT(child, 0);
  EXPECT_EQ(kill(child, 0), 0);  // the policy's own child, in its group
  const auto t1 = std::chrono::steady_clock::now();
  p.reset();  // no 2 s grace after an interrupt: the group is killed at once
  EXPECT_LT(seconds_since(t1), 1.0);
  EXPECT_TRUE(policy::external_policies_interrupted());
  policy::clear_external_interrupt();
  // the child was killed with the group (a zombie until whoever adopted it reaps it)
  bool running = true;
  for (int i = 0; i < 100 && running; ++i) {
    std::ifstream stat("/proc/" + std::to_string(child) + "/stat");
    std::string line;
    running = std::getline(stat, line) && line.substr(line.rfind(')') + 2, 1) != "Z";
    if (running) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_FALSE(running) << "the policy's child " << child << " survived its group";
  if (running) kill(child, SIGKILL);
  std::remove(pid_file.c_str());
}

TEST(ExternalPolicy, WellBehavedProcessRoundTrip) {
  // a shell policy that always answers the same action
  const std::string cmd = kReady + R"(while read l; do case "$l" in *'"step"'*) echo '{"action":[0.5,0,0,0,0,0,-1]}';; esac; done)";
  policy::ExternalPolicy p(cmd, sim::TaskId::kPickCube);
  p.reset();
  for (int t = 0; t < 3; ++t) {
    const Action a = p.act(pick_obs());
    EXPECT_DOUBLE_EQ(a(0), 0.5);
    EXPECT_DOUBLE_EQ(a(6), -1.0);
  }
  EXPECT_EQ(p.sha256(), sha256_hex(cmd));
  auto c = p.clone();
  c->reset();
  EXPECT_DOUBLE_EQ(c->act(pick_obs())(0), 0.5);
}


// counts the processes a policy starts: each start appends a line to `file` before the hello
std::string counting_policy(const std::string& file) {
  return "echo started >> '" + file + "'; " + kReady +
         R"(while read l; do case "$l" in *'"step"'*) echo '{"action":[0.25,0,0,0,0,0,1]}';; esac; done)";
}

int lines_in(const std::string& file) {
  std::ifstream in(file);
  int n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

TEST(ExternalPolicy, FirstCloneOfAnUnusedPolicyTakesOverItsProcess) {
  const std::string file = ::testing::TempDir() + "external_starts_" + std::to_string(::getpid()) + ".txt";
  std::remove(file.c_str());
  policy::ExternalPolicy proto(counting_policy(file), sim::TaskId::kPickCube);
  EXPECT_EQ(lines_in(file), 1);
  auto first = proto.clone();  // takes the greeted process
  EXPECT_EQ(lines_in(file), 1);
  auto second = proto.clone();  // the prototype has none left: a new process
  EXPECT_EQ(lines_in(file), 2);
  first->reset();
  second->reset();
  EXPECT_DOUBLE_EQ(first->act(pick_obs())(0), 0.25);
  EXPECT_DOUBLE_EQ(second->act(pick_obs())(0), 0.25);
  // a used policy keeps its process: its clones start their own
  auto third = first->clone();
  EXPECT_EQ(lines_in(file), 3);
  EXPECT_DOUBLE_EQ(first->act(pick_obs())(0), 0.25);
  // the prototype still works after handing its process over: it starts a new one
  proto.reset();
  EXPECT_EQ(lines_in(file), 4);
  EXPECT_DOUBLE_EQ(proto.act(pick_obs())(0), 0.25);
  std::remove(file.c_str());
}

}  // namespace
