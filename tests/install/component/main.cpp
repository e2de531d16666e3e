// One call into one installed component (chosen by ACTIONSHIFT_COMPONENT_<NAME>), so that the program
// links that component's archive and the dependencies its find_package(COMPONENTS) found.
#include <iostream>

#if defined(ACTIONSHIFT_COMPONENT_CORE)
#include <actionshift/core/contract.hpp>
static bool check() { return actionshift::Contract::identity().sha256().size() == 64; }
#elif defined(ACTIONSHIFT_COMPONENT_DATA)
#include <actionshift/data/builtin_manifests.hpp>
static bool check() { return actionshift::data::resolve_manifest("reference9").pool_sha256().size() == 64; }
#elif defined(ACTIONSHIFT_COMPONENT_ADAPT)
#include <actionshift/adapt/registry.hpp>
static bool check() { return !actionshift::adapt::method_names().empty(); }
#elif defined(ACTIONSHIFT_COMPONENT_FIT)
#include <actionshift/adapt/scale_corrector.hpp>
#include <vector>
static bool check() {
  const std::vector<double> cmd{1.0, 1.0, 1.0, 1.0}, obs{0.5, 0.5, 0.5, 0.5};
  const double g = actionshift::adapt::fit_window_gain(cmd, obs, 1.0, 4.0, 0.1, 10.0);
  return g > 0.0;
}
#elif defined(ACTIONSHIFT_COMPONENT_SELFTEST)
#include <actionshift/selftest/library.hpp>
static bool check() { return !actionshift::selftest::library().empty(); }
#elif defined(ACTIONSHIFT_COMPONENT_SIM)
#include <actionshift/sim/task.hpp>
static bool check() { return actionshift::sim::task_name(actionshift::sim::TaskId::kPegInsertionSide) == "peg_insertion_side"; }
#elif defined(ACTIONSHIFT_COMPONENT_POLICY)
#include <actionshift/policy/expert.hpp>
static bool check() { return actionshift::policy::make_expert(actionshift::sim::TaskId::kPickCube)->sha256().size() == 64; }
#elif defined(ACTIONSHIFT_COMPONENT_EVAL)
#include <actionshift/eval/job.hpp>
static bool check() { return actionshift::eval::splitmix64(0) == 0xE220A8397B1DCDAFull; }
#elif defined(ACTIONSHIFT_COMPONENT_RENDER)
#include <actionshift/render/camera.hpp>
static bool check() { return actionshift::render::default_camera(actionshift::sim::TaskId::kPickCube).fovy > 0.0; }
#else
#error "tests/install/component/main.cpp has no check for this component: add one"
#endif

int main() {
  const bool ok = check();
  std::cout << (ok ? "ok" : "FAILED") << "\n";
  return ok ? 0 : 1;
}
