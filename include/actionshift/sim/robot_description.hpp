#pragma once
/// \file
/// Robot descriptions parsed from URDF (urdfdom), with meshes loaded through assimp.
/// The result is a plain value type (Eigen only); the Bullet articulation is built from it in src/sim.

#include <Eigen/Geometry>

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::sim {

/// Vertices of one collision mesh, already scaled; Bullet uses their convex hull.
struct MeshData {
  std::string source;                     ///< resolved absolute file path
  std::vector<Eigen::Vector3d> vertices;  ///< [m], in the mesh's own frame (scale applied)
};

/// One collision primitive of a link.
struct CollisionGeometry {
  enum class Type { kBox, kSphere, kCylinder, kMesh };
  Type type{Type::kBox};
  Eigen::Isometry3d origin{Eigen::Isometry3d::Identity()};  ///< shape frame in the link frame
  Eigen::Vector3d size{Eigen::Vector3d::Zero()};  ///< box: full extents [m]; sphere: (r,0,0); cylinder: (r, length, 0), axis z
  std::shared_ptr<const MeshData> mesh;            ///< set for kMesh only
};

/// Mass properties of a link (URDF <inertial>), expressed in the link frame.
struct Inertial {
  double mass{0.0};                                   ///< [kg]
  Eigen::Vector3d com{Eigen::Vector3d::Zero()};       ///< centre of mass in the link frame [m]
  Eigen::Matrix3d inertia{Eigen::Matrix3d::Zero()};   ///< about the COM, link axes [kg m^2]
};

struct LinkDescription {
  std::string name;
  Inertial inertial;
  std::vector<CollisionGeometry> collisions;
};

struct JointDescription {
  enum class Type { kFixed, kRevolute, kContinuous, kPrismatic };
  std::string name;
  Type type{Type::kFixed};
  int parent{-1};                                        ///< index into RobotDescription::links
  int child{-1};                                         ///< index into RobotDescription::links
  Eigen::Isometry3d origin{Eigen::Isometry3d::Identity()};  ///< child frame at q = 0 in the parent link frame
  Eigen::Vector3d axis{Eigen::Vector3d::UnitZ()};        ///< unit, in the child (joint) frame
  double lower{0.0}, upper{0.0};                         ///< [rad] or [m]; continuous: -inf/+inf
  double velocity{0.0}, effort{0.0};                     ///< URDF limits
  double damping{0.0};                                   ///< URDF <dynamics damping>
  std::optional<std::string> mimic_joint;                ///< name of the joint this one mimics
  double mimic_multiplier{1.0}, mimic_offset{0.0};
  bool movable() const { return type != Type::kFixed; }
};

/// A parsed robot: links, joints, and the tree between them.
struct RobotDescription {
  std::string name;
  int root{-1};                          ///< index of the root link
  std::vector<LinkDescription> links;
  std::vector<JointDescription> joints;

  /// Index of a link by name; throws actionshift::InputError naming the robot and the link if absent.
  int link_index(std::string_view link) const;
  /// Index of a joint by name; throws actionshift::InputError naming the robot and the joint if absent.
  int joint_index(std::string_view joint) const;
  /// Joint whose child is `link`, or -1 for the root.
  int parent_joint(int link) const;
  /// Pose of link `link` in the root frame for joint values q (indexed like `joints`, fixed entries ignored).
  Eigen::Isometry3d link_pose(int link, const std::vector<double>& q) const;
};

/// `package://NAME/rest` resolution: NAME -> directory.
using PackageMap = std::map<std::string, std::filesystem::path>;

/// Parse a URDF file. Relative mesh paths resolve against the file's directory,
/// `package://` through `packages`, `file://` as absolute paths. Meshes are loaded (and
/// cached per process) through assimp.
/// throws actionshift::InputError (what() = "<urdf file>: <reason>", one line) on any failure:
/// unreadable URDF, bad XML (urdfdom's own reason is included), XML nested deeper than 64 levels,
/// a link reached twice (kinematic loop) or not connected to the root, unsupported joint type,
/// a revolute/prismatic joint without <limit> or with lower >= upper, negative or non-finite
/// velocity/effort/damping, a non-physical inertia (negative mass, not positive semi-definite, or
/// violating the triangle inequality), non-finite origins or axes, a mimic of a joint that is not a
/// movable non-mimic joint, unknown package, missing or unreadable mesh. Collada meshes are read in
/// their own coordinates (the file's <up_axis> is not applied), like STL and OBJ.
RobotDescription load_urdf_file(const std::filesystem::path& urdf, const PackageMap& packages = {});

/// Parse URDF text; `base_dir` resolves relative mesh paths, `origin_name` names the source in errors.
RobotDescription parse_urdf(std::string_view xml, const std::filesystem::path& base_dir,
                            const PackageMap& packages = {}, std::string_view origin_name = "<urdf>");

/// The project's own Panda (configs/robots/panda.urdf, embedded at build time). Parsed once.
const RobotDescription& panda_description();

/// Text of the embedded Panda URDF.
std::string_view panda_urdf_text();

}  // namespace actionshift::sim
