#include "actionshift/core/input_file.hpp"
#include "actionshift/sim/robot_source.hpp"

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/kinematics.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace actionshift::sim {

namespace {

namespace fs = std::filesystem;

std::string read_bytes(const std::string& path, const std::string& field, const std::string& what, std::uintmax_t max_bytes) {
  try {
    return read_input_file(path, what, max_bytes);
  } catch (const InputError& e) {
    throw InputError(e.source(), field, e.reason());
  }
}

}  // namespace

std::map<std::string, std::string> parse_package_args(const std::vector<std::string>& args) {
  std::map<std::string, std::string> out;
  for (const auto& a : args) {
    const auto eq = a.find('=');
    if (eq == std::string::npos) throw InputError("--package", a, "expected NAME=DIR");
    const std::string name = a.substr(0, eq);
    const std::string dir = a.substr(eq + 1);
    if (name.empty()) throw InputError("--package", a, "the package name is empty");
    if (dir.empty()) throw InputError("--package", a, "the directory is empty");
    if (out.count(name)) throw InputError("--package", a, "package '" + name + "' is given twice");
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw InputError("--package", a, "'" + dir + "' is not a directory");
    out[name] = fs::absolute(dir, ec).lexically_normal().string();
  }
  return out;
}

std::string robot_content_sha256(std::string_view urdf_bytes, const RobotDescription& description) {
  std::set<std::string> sources;
  for (const auto& link : description.links)
    for (const auto& c : link.collisions)
      if (c.type == CollisionGeometry::Type::kMesh && c.mesh) sources.insert(c.mesh->source);
  std::set<std::string> mesh_hashes;
  for (const auto& s : sources) mesh_hashes.insert(sha256_hex(read_bytes(s, "mesh", "a mesh file", kMaxMeshFileBytes)));
  nlohmann::json j = nlohmann::json::object();
  j["urdf"] = sha256_hex(urdf_bytes);
  j["meshes"] = nlohmann::json::array();
  for (const auto& h : mesh_hashes) j["meshes"].push_back(h);
  return sha256_hex(canonical_dump(j));
}

namespace {

// the parts the environment drives must exist: checked here, where the file is known, so a plan
// with a robot that is not a Panda fails when it is made, naming the URDF, and not job by job
void check_drivable(const RobotDescription& desc, const std::string& urdf) {
  const RobotNames names;
  const std::string what = "the environment drives a 7-joint arm ending at link '" + names.tcp_link +
                           "' and the finger joints '" + names.left_finger_joint + "' and '" + names.right_finger_joint + "'";
  const auto has_link = [&](const std::string& n) {
    return std::any_of(desc.links.begin(), desc.links.end(), [&](const LinkDescription& l) { return l.name == n; });
  };
  const auto has_joint = [&](const std::string& n) {
    return std::any_of(desc.joints.begin(), desc.joints.end(), [&](const JointDescription& j) { return j.name == n; });
  };
  if (!has_link(names.tcp_link)) throw InputError(urdf, "robot.tcp_link", "no link named '" + names.tcp_link + "' (" + what + ")");
  for (const std::string* j : {&names.left_finger_joint, &names.right_finger_joint})
    if (!has_joint(*j)) throw InputError(urdf, "robot.fingers", "no joint named '" + *j + "' (" + what + ")");
  int dof = 0;
  try {
    dof = KinematicChain(desc, names.tcp_link).dof();
  } catch (const std::invalid_argument& e) {
    throw InputError(urdf, "robot.arm", e.what());
  }
  if (dof != 7)
    throw InputError(urdf, "robot.arm",
                     "the chain to '" + names.tcp_link + "' has " + std::to_string(dof) + " movable joints, 7 expected");
}

}  // namespace

RobotSource load_robot_source(const std::string& urdf, const std::map<std::string, std::string>& packages) {
  std::error_code ec;
  if (urdf.empty()) throw InputError("--robot", "", "empty path (name a URDF file)");
  if (!fs::exists(fs::status(urdf, ec))) throw InputError(urdf, "robot", "no such URDF file");
  RobotSource r;
  r.urdf = fs::absolute(urdf, ec).lexically_normal().string();
  r.packages = packages;
  PackageMap pm;
  for (const auto& [name, dir] : packages) pm[name] = dir;
  // one read: the bytes hashed are the bytes parsed (a directory, FIFO or oversized file is refused here)
  const std::string bytes = read_bytes(r.urdf, "robot", "a URDF file", kMaxSmallFileBytes);
  auto desc = std::make_shared<RobotDescription>(parse_urdf(bytes, fs::path(r.urdf).parent_path(), pm, r.urdf));
  check_drivable(*desc, urdf);
  r.sha256 = robot_content_sha256(bytes, *desc);
  r.description = std::move(desc);
  return r;
}

}  // namespace actionshift::sim
