#pragma once
/// \file A robot description given by the user (`--robot URDF --package NAME=DIR`): the parsed
/// description and its content hash, which enters a job's identity (docs/formats.md, "Job spec").
///
/// The hash covers what the simulation reads: the URDF's bytes and the bytes of every collision mesh
/// it references (sorted, so the hash does not depend on where the files live or which package
/// names point at them). Visual meshes are not loaded and do not enter it.

#include "actionshift/sim/robot_description.hpp"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace actionshift::sim {

/// A user-supplied robot: its parsed description and content hash.
struct RobotSource {
  std::string urdf;                              ///< absolute path of the URDF file
  std::map<std::string, std::string> packages;   ///< package name -> absolute directory
  std::string sha256;                            ///< content hash (see the file comment)
  std::shared_ptr<const RobotDescription> description;
};

/// Parses `NAME=DIR` arguments (`--package`). Throws actionshift::InputError("--package", arg, reason)
/// for a missing '=', an empty or repeated name, or a directory that does not exist.
std::map<std::string, std::string> parse_package_args(const std::vector<std::string>& args);

/// Loads a URDF with its meshes (load_urdf_file) and hashes it. Throws actionshift::InputError naming
/// the file and reason when the URDF or a mesh cannot be read or parsed.
RobotSource load_robot_source(const std::string& urdf, const std::map<std::string, std::string>& packages);

/// SHA-256 of {"meshes":[sorted sha256 of each distinct collision mesh file],"urdf":sha256(URDF bytes)}
/// in canonical JSON. `description` must be the one parsed from `urdf_bytes`.
std::string robot_content_sha256(std::string_view urdf_bytes, const RobotDescription& description);

}  // namespace actionshift::sim
