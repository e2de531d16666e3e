// the external-policy protocol: reply lines to step requests and to the hello
#include "actionshift/policy/external.hpp"
#include "harness.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  const std::string_view reply = fuzz::text(data, size);
  (void)policy::is_ready_reply(reply);
  fuzz::expect_input_errors([&] {
    const Action a = policy::parse_step_reply(reply);
    if (!a.allFinite()) throw std::logic_error("a non-finite action was accepted");
  });
  return 0;
}
