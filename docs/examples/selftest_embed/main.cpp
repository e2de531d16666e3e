// Embedding the plug-and-verify self-test in your own control loop (docs/selftest.md).
// The "robot" is a toy kinematic point robot defined here: it decodes each raw command through a
// hidden wiring (x and y swapped, roll negated) and moves its TCP by 2 cm / 0.05 rad per unit, plus
// sensor noise. The self-test never sees the wiring: it asks for probes, we send them and report
// the measured pose. Run: ./selftest_embed  (prints the report; exit code 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE)
#include <actionshift/core/decoder.hpp>
#include <actionshift/core/rng.hpp>
#include <actionshift/core/transforms.hpp>
#include <actionshift/selftest/selftest.hpp>

#include <Eigen/Geometry>
#include <iostream>

using namespace actionshift;

struct ToyRobot {
  Decoder wiring = Decoder(Contract::make({{1, 0, 2, 3, 4, 5}, {1, 1, 1, -1, 1, 1}, {1, 1, 1, 1, 1, 1}}));
  Eigen::Vector3d position{0.3, 0.0, 0.2};                          // [m]
  Eigen::Quaterniond orientation{Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX())};  // tool pointing down
  Rng noise{42};

  void send(const Action& raw) {  // the hidden wiring decodes in the live tool frame
    const Action c = wiring.step(raw, orientation.toRotationMatrix());
    for (int i = 0; i < 3; ++i) position[i] += 0.02 * c[i] + 0.0005 * noise.normal();
    Eigen::Vector3d rv = 0.05 * c.segment<3>(3);
    for (int i = 0; i < 3; ++i) rv[i] += 0.001 * noise.normal();
    orientation = (Eigen::AngleAxisd(rv.norm(), rv.normalized()) * orientation).normalized();
  }
  selftest::TcpPose measure() const {
    selftest::TcpPose p;
    p.position = position;
    p.quaternion = {orientation.w(), orientation.x(), orientation.y(), orientation.z()};
    return p;
  }
};

int main() {
  selftest::Options o;  // expects identity wiring; library pool; entropy probes; budget 6; |probe| <= 0.5
  o.model.alpha = {0.02, 0.02, 0.02, 0.05, 0.05, 0.05};      // response per unit command, as calibrated
  o.model.sigma = {0.0005, 0.0005, 0.0005, 0.001, 0.001, 0.001};
  std::string err;
  auto test = selftest::SelfTest::create(o, &err);  // no exceptions on this path
  if (!test) {
    std::cerr << err << "\n";
    return 3;
  }
  ToyRobot robot;
  test->begin(robot.measure());
  while (auto raw = test->next_probe()) {  // nullopt once the budget is spent
    robot.send(*raw);
    if (!test->try_observe(robot.measure(), &err)) return std::cerr << err << "\n", 3;
  }
  const selftest::Verdict v = test->verdict();
  selftest::ReportHeader h;
  h.task = "toy point robot";
  h.budget = o.budget;
  h.pool_size = static_cast<int>(test->pool().size());
  std::cout << selftest::to_text(v, h);
  return v.exit_code();
}
