#include "actionshift/eval/provenance.hpp"

#include <nlohmann/json.hpp>

#ifndef ACTIONSHIFT_VERSION_STRING
#error "ACTIONSHIFT_VERSION_STRING must be defined by the build (src/eval/CMakeLists.txt)"
#endif
#ifndef ACTIONSHIFT_GIT_COMMIT
#define ACTIONSHIFT_GIT_COMMIT ""
#endif

namespace actionshift::eval {

const Provenance& build_provenance() {
  static const Provenance p{ACTIONSHIFT_VERSION_STRING, ACTIONSHIFT_GIT_COMMIT};
  return p;
}

nlohmann::json provenance_to_json(const Provenance& p) {
  nlohmann::json j = nlohmann::json::object();
  j["actionshift_version"] = p.version;
  j["git_commit"] = p.git_commit.empty() ? nlohmann::json(nullptr) : nlohmann::json(p.git_commit);
  return j;
}

}  // namespace actionshift::eval
