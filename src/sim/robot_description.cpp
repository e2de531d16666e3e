// urdf parsing (urdfdom) and mesh loading (assimp) into the plain RobotDescription value type
#include "actionshift/sim/robot_description.hpp"

#include "actionshift/core/error.hpp"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <urdf_parser/urdf_parser.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace actionshift::embedded {
extern const std::string_view panda_urdf;
}

namespace actionshift::sim {
namespace {

Eigen::Isometry3d to_iso(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  double x = 0, y = 0, z = 0, w = 1;
  p.rotation.getQuaternion(x, y, z, w);
  t.linear() = Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

[[noreturn]] void fail(std::string_view origin, const std::string& what) {
  throw InputError(std::string(origin), "", what);
}

// process-wide cache of unscaled meshes keyed by resolved path
std::shared_ptr<const MeshData> load_mesh_cached(const std::filesystem::path& file, std::string_view origin) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const MeshData>> cache;
  const std::string key = file.lexically_normal().string();
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    fail(origin, "mesh file not found: " + key);
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(key, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (scene == nullptr || scene->mRootNode == nullptr || scene->mNumMeshes == 0)
    fail(origin, "cannot read mesh " + key + " (" + importer.GetErrorString() + ")");
  auto mesh = std::make_shared<MeshData>();
  mesh->source = key;
  // walk the node tree so node transforms are applied
  std::function<void(const aiNode*, const aiMatrix4x4&)> walk = [&](const aiNode* node, const aiMatrix4x4& parent) {
    const aiMatrix4x4 m = parent * node->mTransformation;
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const aiMesh* am = scene->mMeshes[node->mMeshes[i]];
      for (unsigned v = 0; v < am->mNumVertices; ++v) {
        const aiVector3D p = m * am->mVertices[v];
        mesh->vertices.emplace_back(p.x, p.y, p.z);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) walk(node->mChildren[c], m);
  };
  walk(scene->mRootNode, aiMatrix4x4());
  if (mesh->vertices.size() < 4) fail(origin, "mesh " + key + " has fewer than 4 vertices");
  std::lock_guard<std::mutex> lock(mutex);
  return cache.emplace(key, std::move(mesh)).first->second;
}

std::filesystem::path resolve_uri(const std::string& uri, const std::filesystem::path& base_dir,
                                  const PackageMap& packages, std::string_view origin) {
  constexpr std::string_view kPackage = "package://";
  constexpr std::string_view kFile = "file://";
  if (uri.rfind(kPackage, 0) == 0) {
    const std::string rest = uri.substr(kPackage.size());
    const auto slash = rest.find('/');
    const std::string pkg = rest.substr(0, slash);
    const auto it = packages.find(pkg);
    if (it == packages.end()) fail(origin, "mesh " + uri + ": package '" + pkg + "' not in the package map");
    return slash == std::string::npos ? it->second : it->second / rest.substr(slash + 1);
  }
  if (uri.rfind(kFile, 0) == 0) return std::filesystem::path(uri.substr(kFile.size()));
  std::filesystem::path p(uri);
  return p.is_absolute() ? p : base_dir / p;
}

}  // namespace

int RobotDescription::link_index(std::string_view link) const {
  for (std::size_t i = 0; i < links.size(); ++i)
    if (links[i].name == link) return static_cast<int>(i);
  throw std::out_of_range("robot '" + name + "' has no link '" + std::string(link) + "'");
}

int RobotDescription::joint_index(std::string_view joint) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == joint) return static_cast<int>(i);
  throw std::out_of_range("robot '" + name + "' has no joint '" + std::string(joint) + "'");
}

int RobotDescription::parent_joint(int link) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].child == link) return static_cast<int>(i);
  return -1;
}

Eigen::Isometry3d RobotDescription::link_pose(int link, const std::vector<double>& q) const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int l = link; l != root;) {
    const int j = parent_joint(l);
    if (j < 0) break;
    const JointDescription& jd = joints[static_cast<std::size_t>(j)];
    const double v = static_cast<std::size_t>(j) < q.size() ? q[static_cast<std::size_t>(j)] : 0.0;
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    if (jd.type == JointDescription::Type::kRevolute || jd.type == JointDescription::Type::kContinuous)
      motion.linear() = Eigen::AngleAxisd(v, jd.axis).toRotationMatrix();
    else if (jd.type == JointDescription::Type::kPrismatic)
      motion.translation() = v * jd.axis;
    t = jd.origin * motion * t;
    l = jd.parent;
  }
  return t;
}

RobotDescription parse_urdf(std::string_view xml, const std::filesystem::path& base_dir, const PackageMap& packages,
                            std::string_view origin) {
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(std::string(xml));
  if (!model || !model->getRoot()) fail(origin, "not a valid URDF (urdfdom could not parse it)");
  RobotDescription out;
  out.name = model->getName();

  // depth-first over the tree so every parent precedes its children
  std::vector<urdf::LinkConstSharedPtr> order;
  std::function<void(const urdf::LinkConstSharedPtr&)> visit = [&](const urdf::LinkConstSharedPtr& l) {
    order.push_back(l);
    for (const auto& child : l->child_links) visit(child);
  };
  visit(model->getRoot());
  std::map<std::string, int> index;
  for (const auto& l : order) index[l->name] = static_cast<int>(index.size());
  out.root = 0;

  for (const auto& l : order) {
    LinkDescription ld;
    ld.name = l->name;
    if (l->inertial) {
      const Eigen::Isometry3d o = to_iso(l->inertial->origin);
      Eigen::Matrix3d in;
      in << l->inertial->ixx, l->inertial->ixy, l->inertial->ixz, l->inertial->ixy, l->inertial->iyy,
          l->inertial->iyz, l->inertial->ixz, l->inertial->iyz, l->inertial->izz;
      ld.inertial.mass = l->inertial->mass;
      ld.inertial.com = o.translation();
      ld.inertial.inertia = o.linear() * in * o.linear().transpose();
      if (!(ld.inertial.mass >= 0.0) || !std::isfinite(ld.inertial.mass))
        fail(origin, "link " + l->name + ": inertial mass must be finite and >= 0");
    }
    for (const auto& c : l->collision_array) {
      if (!c || !c->geometry) continue;
      CollisionGeometry g;
      g.origin = to_iso(c->origin);
      switch (c->geometry->type) {
        case urdf::Geometry::BOX: {
          const auto& b = static_cast<const urdf::Box&>(*c->geometry);
          g.type = CollisionGeometry::Type::kBox;
          g.size = Eigen::Vector3d(b.dim.x, b.dim.y, b.dim.z);
          break;
        }
        case urdf::Geometry::SPHERE: {
          const auto& s = static_cast<const urdf::Sphere&>(*c->geometry);
          g.type = CollisionGeometry::Type::kSphere;
          g.size = Eigen::Vector3d(s.radius, 0, 0);
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& s = static_cast<const urdf::Cylinder&>(*c->geometry);
          g.type = CollisionGeometry::Type::kCylinder;
          g.size = Eigen::Vector3d(s.radius, s.length, 0);
          break;
        }
        case urdf::Geometry::MESH: {
          const auto& m = static_cast<const urdf::Mesh&>(*c->geometry);
          g.type = CollisionGeometry::Type::kMesh;
          const auto file = resolve_uri(m.filename, base_dir, packages, origin);
          auto raw = load_mesh_cached(file, origin);
          const Eigen::Vector3d s(m.scale.x, m.scale.y, m.scale.z);
          if (s == Eigen::Vector3d::Ones()) {
            g.mesh = raw;
          } else {
            auto scaled = std::make_shared<MeshData>(*raw);
            for (auto& v : scaled->vertices) v = v.cwiseProduct(s);
            g.mesh = std::move(scaled);
          }
          break;
        }
      }
      ld.collisions.push_back(std::move(g));
    }
    out.links.push_back(std::move(ld));
  }

  for (const auto& l : order) {
    for (const auto& j : l->child_joints) {
      JointDescription jd;
      jd.name = j->name;
      jd.parent = index.at(j->parent_link_name);
      jd.child = index.at(j->child_link_name);
      jd.origin = to_iso(j->parent_to_joint_origin_transform);
      switch (j->type) {
        case urdf::Joint::REVOLUTE: jd.type = JointDescription::Type::kRevolute; break;
        case urdf::Joint::CONTINUOUS: jd.type = JointDescription::Type::kContinuous; break;
        case urdf::Joint::PRISMATIC: jd.type = JointDescription::Type::kPrismatic; break;
        case urdf::Joint::FIXED: jd.type = JointDescription::Type::kFixed; break;
        default: fail(origin, "joint " + j->name + ": only fixed, revolute, continuous and prismatic joints are supported");
      }
      Eigen::Vector3d axis(j->axis.x, j->axis.y, j->axis.z);
      if (jd.movable()) {
        if (!(axis.norm() > 1e-12)) fail(origin, "joint " + j->name + ": zero axis");
        jd.axis = axis.normalized();
      }
      if (jd.type == JointDescription::Type::kContinuous) {
        jd.lower = -std::numeric_limits<double>::infinity();
        jd.upper = std::numeric_limits<double>::infinity();
      }
      if (j->limits) {
        if (jd.type != JointDescription::Type::kContinuous) {
          jd.lower = j->limits->lower;
          jd.upper = j->limits->upper;
        }
        jd.velocity = j->limits->velocity;
        jd.effort = j->limits->effort;
      }
      if (j->dynamics) jd.damping = j->dynamics->damping;
      if (j->mimic) {
        jd.mimic_joint = j->mimic->joint_name;
        jd.mimic_multiplier = j->mimic->multiplier;
        jd.mimic_offset = j->mimic->offset;
      }
      out.joints.push_back(std::move(jd));
    }
  }
  return out;
}

RobotDescription load_urdf_file(const std::filesystem::path& urdf, const PackageMap& packages) {
  std::ifstream in(urdf, std::ios::binary);
  if (!in) fail(urdf.string(), "cannot open URDF file");
  std::stringstream ss;
  ss << in.rdbuf();
  const auto dir = std::filesystem::absolute(urdf).parent_path();
  return parse_urdf(ss.str(), dir, packages, urdf.string());
}

std::string_view panda_urdf_text() { return embedded::panda_urdf; }

const RobotDescription& panda_description() {
  static const RobotDescription panda = parse_urdf(embedded::panda_urdf, std::filesystem::path("."), {}, "<embedded panda.urdf>");
  return panda;
}

}  // namespace actionshift::sim
