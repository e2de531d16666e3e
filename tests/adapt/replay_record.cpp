// Writes the probe-selection replay fixture (tests/adapt/data/probe_replay.json; see replay.hpp):
//   build/tests/adapt/actionshift_probe_replay_record > tests/adapt/data/probe_replay.json
// The committed fixture was recorded before the selection code was rewritten for speed; re-record
// only when a decision is meant to change.
#include "replay.hpp"

#include <iostream>

int main() {
  using actionshift::testing::ReplaySpec;
  // the maniskill pick_cube calibration (configs/calibration/maniskill/pick_cube.json) and the
  // pick-like model of the unit tests (lower SNR, so beliefs stay ambiguous for longer)
  const actionshift::adapt::ResponseModel sim{
      {0.034444301519877187, 0.023761665290694078, 0.02156294797703972, 0.0337292463468545, 0.028423489983690473,
       0.03186759879711181},
      {0.006598786003639606, 0.008197477387691604, 0.009413154034377539, 0.00714837466411989, 0.026625840464159414,
       0.021391477726535452}};
  const actionshift::adapt::ResponseModel pick{{0.032, 0.016, 0.018, -0.035, -0.027, -0.038},
                                               {0.03, 0.02, 0.02, 0.04, 0.05, 0.04}};
  std::vector<ReplaySpec> specs;
  for (const char* method : {"entropy_probes", "dualabi"}) {
    int i = 0;
    for (int truth : {1, 4, 7, 8}) {
      specs.push_back({method, nlohmann::json::object(), "reference9", i % 2 ? pick : sim, truth, 100u + static_cast<unsigned>(i), 10});
      ++i;
    }
    for (int truth : {71, 102, 171}) {  // tool-frame absolute, lag 2, tool-frame lag 1
      specs.push_back({method, nlohmann::json::object(), "full", i % 2 ? pick : sim, truth, 100u + static_cast<unsigned>(i), 8});
      ++i;
    }
  }
  // DualABI probing the whole budget (τ = 0): selections from later, sharper beliefs
  specs.push_back({"dualabi", {{"tau", 0.0}}, "reference9", sim, 5, 200, 10});
  specs.push_back({"dualabi", {{"tau", 0.0}}, "full", sim, 130, 201, 8});
  nlohmann::json out;
  out["schema"] = "actionshift-probe-replay/1";
  out["recorded_by"] = "tests/adapt/replay_record.cpp";
  out["episodes"] = nlohmann::json::array();
  for (const auto& s : specs) out["episodes"].push_back(actionshift::testing::record_episode(s));
  std::cout << out.dump() << "\n";
}
