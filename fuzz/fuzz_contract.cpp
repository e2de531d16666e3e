// contract JSON (Contract::from_json): `contract hash|decode|encode`, manifests, selftest arguments
#include "actionshift/core/contract.hpp"
#include "harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  fuzz::expect_input_errors([&] {
    const Contract c = Contract::from_json(fuzz::text(data, size));
    // a parsed contract round-trips through its canonical JSON
    if (Contract::from_json(c.to_json()) != c) throw std::logic_error("contract JSON round trip differs");
  });
  return 0;
}
