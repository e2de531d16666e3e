// MLP weight files (.asmlp: magic, version, JSON header, float payload)
#include "actionshift/policy/mlp.hpp"
#include "harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  fuzz::expect_input_errors([&] { (void)policy::parse_mlp(fuzz::text(data, size), "fuzz.asmlp"); });
  return 0;
}
