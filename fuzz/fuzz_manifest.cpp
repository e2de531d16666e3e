// split manifests and pools (Manifest::parse, then every validation check without regeneration)
#include "actionshift/core/manifest.hpp"
#include "actionshift/core/validate.hpp"
#include "harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  fuzz::expect_input_errors([&] {
    const Manifest m = Manifest::parse(fuzz::text(data, size), "fuzz.json");
    (void)validate(m, /*regenerate=*/false);
    (void)m.computed_sha256();
  });
  return 0;
}
