// experiment YAML (eval::parse_experiment)
#include "actionshift/eval/experiment_yaml.hpp"
#include "harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  fuzz::expect_input_errors([&] { (void)eval::parse_experiment(fuzz::text(data, size), "fuzz.yaml"); });
  return 0;
}
