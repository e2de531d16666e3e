// robot descriptions: URDF text through the loader (urdfdom, then the project's checks), in memory,
// with relative mesh paths resolving into an empty directory
#include "actionshift/sim/robot_description.hpp"
#include "harness.hpp"

#include <cstdlib>
#include <filesystem>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  static const std::filesystem::path empty = [] {
    char tmpl[] = "/tmp/actionshift_fuzz_urdf_XXXXXX";
    const char* made = ::mkdtemp(tmpl);
    if (made == nullptr) std::abort();
    return std::filesystem::path(made);
  }();
  const std::string_view xml = fuzz::text(data, size);
  // absolute mesh paths would load arbitrary files of the machine: out of scope here
  if (xml.find("file:") != std::string_view::npos || xml.find("=\"/") != std::string_view::npos ||
      xml.find("='/") != std::string_view::npos)
    return 0;
  fuzz::expect_input_errors([&] {
    const sim::RobotDescription d = sim::parse_urdf(xml, empty, {}, "fuzz.urdf");
    for (std::size_t l = 0; l < d.links.size(); ++l) (void)d.link_pose(static_cast<int>(l), {});
  });
  return 0;
}
