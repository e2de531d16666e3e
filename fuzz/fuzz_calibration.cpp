// response calibrations (configs/calibration/<task>.json, selftest --calibration)
#include "actionshift/adapt/calibration.hpp"
#include "harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  fuzz::expect_input_errors([&] {
    const auto c = adapt::ResponseCalibration::from_json(std::string(fuzz::text(data, size)), "fuzz.json");
    (void)c.sha256();
    (void)c.model();
  });
  return 0;
}
