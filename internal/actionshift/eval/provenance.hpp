#pragma once
/// \file Provenance of results: the ActionShift version and git commit of the build that wrote them
/// (docs/formats.md, "Episode record" and "Job summary").

#include <nlohmann/json_fwd.hpp>

#include <string>

namespace actionshift::eval {

/// What built this library. `git_commit` is the commit checked out when CMake configured the build
/// (40 hex digits, with "-dirty" appended if tracked files had uncommitted changes then), or "" when
/// the sources were not a git checkout.
struct Provenance {
  std::string version;     ///< project version, e.g. "0.1.0"
  std::string git_commit;  ///< configure-time commit, or ""
  bool operator==(const Provenance&) const = default;
};

/// This build's provenance (compile-time constants).
const Provenance& build_provenance();

/// {"actionshift_version": ..., "git_commit": ... or null}
nlohmann::json provenance_to_json(const Provenance& p);

}  // namespace actionshift::eval
