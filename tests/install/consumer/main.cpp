// Decodes one action with an installed ActionShift and prints two golden hashes.
#include <actionshift/core/decoder.hpp>
#include <actionshift/core/reference_contracts.hpp>
#include <actionshift/data/builtin_manifests.hpp>

#include <iostream>

int main() {
  using namespace actionshift;
  Decoder d(reference::oracle_contract());
  Action raw;
  raw << 0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7;
  const Action canonical = d.step(raw);
  const Manifest pool = data::resolve_manifest("reference9");
  std::cout << "identity " << Contract::identity().sha256() << "\n"
            << "reference9 pool " << pool.pool_sha256() << "\n"
            << "canonical[1] " << canonical[1] << "\n";
  return canonical[1] == 0.2 ? 0 : 1;
}
