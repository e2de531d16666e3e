// the self-test's contract arguments (--expected, --hidden-contract): library names,
// MANIFEST:INDEX, inline contract JSON (file paths are left to fuzz_contract)
#include "cmd_selftest.hpp"
#include "harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  const std::string arg(fuzz::text(data, size));
  if (arg.find('/') != std::string::npos || arg.find('\0') != std::string::npos) return 0;
  fuzz::expect_input_errors([&] { (void)cli::resolve_contract_arg(arg, "--expected"); });
  return 0;
}
