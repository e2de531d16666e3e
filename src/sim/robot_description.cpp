// urdf parsing (urdfdom) and mesh loading (assimp) into the plain RobotDescription value type
#include "actionshift/core/input_file.hpp"
#include "actionshift/sim/robot_description.hpp"

#include "actionshift/core/error.hpp"

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <set>
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

constexpr std::size_t kMaxMeshNodes = 100000;  // scene-graph nodes per mesh file
constexpr int kMaxXmlDepth = 64;                // element nesting; a URDF needs about 5
constexpr double kMaxLinkMassKg = 1e6;          // a link's mass; the Panda's weigh 0.015-4.97 kg

// process-wide cache of unscaled meshes keyed by resolved path
std::shared_ptr<const MeshData> load_mesh_cached(const std::filesystem::path& file, std::string_view origin) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const MeshData>> cache;
  const std::string key = file.lexically_normal().string();
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
  }
  const std::string shown = quote_input(key, '\'', 300);  // a path from the URDF, quoted and cut
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::status(file, ec)))
    fail(origin, "mesh file not found: " + shown);
  // a special or oversized file is refused before assimp opens it (it reads the whole file)
  try {
    (void)check_input_file(key, "a mesh file", kMaxMeshFileBytes);
  } catch (const InputError& e) {
    fail(origin, "mesh " + shown + ": " + e.reason());
  }
  Assimp::Importer importer;
  // Collada files carry an <up_axis>; assimp rotates Z_UP files into its Y-up convention by default,
  // which would turn a .dae collision mesh 90 degrees about x relative to its STL/OBJ twin. A URDF
  // mesh's vertices are coordinates in the link frame, whatever the exporter's notion of "up".
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFile(key, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (scene == nullptr || scene->mRootNode == nullptr || scene->mNumMeshes == 0)
    fail(origin, "cannot read mesh " + shown + " (" + importer.GetErrorString() + ")");
  auto mesh = std::make_shared<MeshData>();
  mesh->source = key;
  // walk the node tree (explicitly, a hostile file may nest nodes deeply) so node transforms are applied
  std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{scene->mRootNode, aiMatrix4x4()}};
  std::size_t visited = 0;
  while (!stack.empty()) {
    const auto [node, parent] = stack.back();
    stack.pop_back();
    if (++visited > kMaxMeshNodes) fail(origin, "mesh " + shown + " has more than " + std::to_string(kMaxMeshNodes) + " nodes");
    const aiMatrix4x4 m = parent * node->mTransformation;
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      if (node->mMeshes[i] >= scene->mNumMeshes) fail(origin, "mesh " + shown + ": a node names a mesh that does not exist");
      const aiMesh* am = scene->mMeshes[node->mMeshes[i]];
      for (unsigned v = 0; v < am->mNumVertices; ++v) {
        const aiVector3D p = m * am->mVertices[v];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
          fail(origin, "mesh " + shown + " has a non-finite vertex");
        mesh->vertices.emplace_back(p.x, p.y, p.z);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) stack.emplace_back(node->mChildren[c], m);
  }
  if (mesh->vertices.size() < 4) fail(origin, "mesh " + shown + " has fewer than 4 vertices");
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
    if (it == packages.end())
      fail(origin, "mesh " + quote_input(uri, '\'', 300) + ": package " + quote_input(pkg) +
                       " not in the package map (give --package NAME=DIR)");
    return slash == std::string::npos ? it->second : it->second / rest.substr(slash + 1);
  }
  if (uri.rfind(kFile, 0) == 0) return std::filesystem::path(uri.substr(kFile.size()));
  std::filesystem::path p(uri);
  return p.is_absolute() ? p : base_dir / p;
}

// Deepest element nesting of an XML text, computed without recursion. urdfdom's XML parser
// (tinyxml) recurses once per nesting level, so a hostile file nested 100,000 deep would overflow
// the stack before urdfdom could reject it; this scan runs first. Comments, CDATA, processing
// instructions, declarations and quoted attribute values are skipped.
int xml_depth(std::string_view xml) {
  int depth = 0, deepest = 0;
  std::size_t i = 0;
  const auto skip_past = [&](std::string_view end) {
    const auto e = xml.find(end, i);
    i = e == std::string_view::npos ? xml.size() : e + end.size();
  };
  while ((i = xml.find('<', i)) != std::string_view::npos) {
    const std::string_view rest = xml.substr(i);
    if (rest.starts_with("<!--")) { skip_past("-->"); continue; }
    if (rest.starts_with("<![CDATA[")) { skip_past("]]>"); continue; }
    if (rest.starts_with("<?")) { skip_past("?>"); continue; }
    if (rest.starts_with("<!")) { skip_past(">"); continue; }
    const bool closing = rest.starts_with("</");
    char quote = 0, last = 0;
    for (++i; i < xml.size(); ++i) {
      const char c = xml[i];
      if (quote != 0) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        break;
      } else if (c != ' ' && c != '\t' && c != '\n' && c != '\r') {
        last = c;
      }
    }
    if (closing) {
      depth = depth > 0 ? depth - 1 : 0;
    } else if (last != '/') {
      deepest = std::max(deepest, ++depth);
    }
    if (i < xml.size()) ++i;
  }
  return deepest;
}

// Collects what urdfdom reports through console_bridge while it parses, so the reason for a
// rejection reaches the project's one-line error instead of stderr. console_bridge's handler is
// process-global, hence the mutex around every parse.
class CapturingHandler final : public console_bridge::OutputHandler {
 public:
  // urdfdom reports the specific cause first ("Joint [j] is of type REVOLUTE but it does not
  // specify limits") and a generic one last ("joint xml is not initialized correctly"): keep both
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN && first_.empty()) first_ = text;
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      if (first_error_.empty()) first_error_ = text;
      last_error_ = text;
    }
  }
  std::string reason() const {
    if (first_error_.empty()) return first_;
    return last_error_ == first_error_ ? first_error_ : first_error_ + "; " + last_error_;
  }
  bool any_error() const { return !first_error_.empty(); }

 private:
  std::string first_, first_error_, last_error_;
};

// The joint graph, read before urdfdom builds its tree. urdfdom links every joint's child into its
// parent's child list first and checks the tree afterwards: a file it then rejects (a second root,
// no root) after a joint has closed a cycle leaves links owning each other that it never frees
// (found by the urdf fuzz target). Rejecting a second parent or a cycle here means urdfdom never
// builds one. Read with TinyXML, urdfdom's own parser (xml_depth has bounded its recursion); a file
// TinyXML cannot read is left to urdfdom, which reports the reason.
std::string joint_graph_problem(const std::string& xml) {
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  const TiXmlElement* robot = doc.Error() ? nullptr : doc.FirstChildElement("robot");
  if (robot == nullptr) return {};
  std::map<std::string, std::pair<std::string, std::string>> parent_of;  // child link -> (parent link, joint)
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j != nullptr; j = j->NextSiblingElement("joint")) {
    const TiXmlElement* p = j->FirstChildElement("parent");
    const TiXmlElement* c = j->FirstChildElement("child");
    const char* parent = p != nullptr ? p->Attribute("link") : nullptr;
    const char* child = c != nullptr ? c->Attribute("link") : nullptr;
    const char* name = j->Attribute("name");
    if (parent == nullptr || child == nullptr) continue;  // urdfdom rejects it and says why
    const auto [it, fresh] = parent_of.emplace(child, std::make_pair(std::string(parent), std::string(name ? name : "?")));
    if (!fresh)
      return "link " + std::string(child) + ": child of two joints (" + it->second.second + " and " + (name ? name : "?") +
             "), a kinematic loop or a second parent; only kinematic trees are supported";
  }
  // one parent per link: a cycle is a chain of parents that comes back to a link of the same walk
  std::map<std::string, int> state;  // 1 on the current walk, 2 finished
  for (const auto& start : parent_of) {
    std::vector<std::string> walk;
    std::string link = start.first;
    while (true) {
      const int s = state[link];
      if (s == 1) return "joints form a kinematic loop through link " + link + "; only kinematic trees are supported";
      if (s == 2) break;
      state[link] = 1;
      walk.push_back(link);
      const auto up = parent_of.find(link);
      if (up == parent_of.end()) break;
      link = up->second.first;
    }
    for (const auto& l : walk) state[l] = 2;
  }
  return {};
}

urdf::ModelInterfaceSharedPtr parse_with_reason(const std::string& xml, std::string_view origin) {
  if (const std::string why = joint_graph_problem(xml); !why.empty()) fail(origin, why);
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  CapturingHandler handler;
  console_bridge::useOutputHandler(&handler);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    console_bridge::restorePreviousOutputHandler();
    fail(origin, std::string("not a valid URDF: ") + e.what());
  }
  console_bridge::restorePreviousOutputHandler();
  // urdfdom can log an error and still return a model: a link whose <inertial> or <collision> it could
  // not read (a "nan" mass, a size it cannot parse) comes back with no mass and no collisions
  if (!model || !model->getRoot() || handler.any_error()) {
    std::string why = handler.reason();
    for (char& c : why) if (c == '\n' || c == '\r') c = ' ';
    while (!why.empty() && why.back() == ' ') why.pop_back();
    fail(origin, "not a valid URDF: " + (why.empty() ? std::string("urdfdom could not parse it") : why));
  }
  // urdfdom links own their children (shared_ptr) and point to their parent weakly; a joint closing a
  // kinematic loop makes an ownership cycle that would outlive the model. The returned handle owns the
  // model and cuts every child list when it is released, so a rejected loop frees everything.
  // joint_graph_problem rejects loops first, but only in files TinyXML reads; this cut also covers
  // the rest.
  return urdf::ModelInterfaceSharedPtr(model.get(), [model](urdf::ModelInterface*) {
    for (auto& [name, link] : model->links_)
      if (link) {
        link->child_links.clear();
        link->child_joints.clear();
      }
  });
}

bool finite(const Eigen::Isometry3d& t) { return t.matrix().allFinite(); }

// A physical inertia tensor: finite, symmetric, positive semi-definite, and its principal moments
// obey the triangle inequality (no moment exceeds the sum of the other two).
std::string inertia_problem(const Eigen::Matrix3d& in) {
  if (!in.allFinite()) return "inertia is not finite";
  const Eigen::Vector3d m = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(in, Eigen::EigenvaluesOnly).eigenvalues();
  const double tol = 1e-9 * std::max(1.0, m.cwiseAbs().maxCoeff());
  if (m.minCoeff() < -tol) return "inertia is not positive semi-definite (a principal moment is negative)";
  if (m(2) > m(0) + m(1) + tol) return "inertia violates the triangle inequality (one principal moment exceeds the sum of the other two)";
  return {};
}

}  // namespace

int RobotDescription::link_index(std::string_view link) const {
  for (std::size_t i = 0; i < links.size(); ++i)
    if (links[i].name == link) return static_cast<int>(i);
  throw InputError("robot '" + name + "'", "link", "no link named '" + std::string(link) + "'");
}

int RobotDescription::joint_index(std::string_view joint) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == joint) return static_cast<int>(i);
  throw InputError("robot '" + name + "'", "joint", "no joint named '" + std::string(joint) + "'");
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
  if (xml_depth(xml) > kMaxXmlDepth)
    fail(origin, "not a valid URDF: XML elements nested deeper than " + std::to_string(kMaxXmlDepth) + " levels");
  const urdf::ModelInterfaceSharedPtr model = parse_with_reason(std::string(xml), origin);
  RobotDescription out;
  out.name = model->getName();

  // depth-first over the tree so every parent precedes its children; iterative, and a link reached
  // twice (a joint closing a loop, or a link with two parent joints) is rejected: urdfdom keeps only
  // the last parent of such a link and would leave a cycle behind
  std::vector<urdf::LinkConstSharedPtr> order;
  std::set<std::string> seen;
  std::vector<urdf::LinkConstSharedPtr> pending{model->getRoot()};
  while (!pending.empty()) {
    const urdf::LinkConstSharedPtr l = pending.back();
    pending.pop_back();
    if (!seen.insert(l->name).second)
      fail(origin, "link " + l->name + ": reached twice from the root (a kinematic loop or two parent joints); "
                   "only kinematic trees are supported");
    order.push_back(l);
    for (auto it = l->child_links.rbegin(); it != l->child_links.rend(); ++it) pending.push_back(*it);
  }
  if (order.size() != model->links_.size())
    fail(origin, "not a valid URDF: " + std::to_string(model->links_.size() - std::min(model->links_.size(), order.size())) +
                     " link(s) are not connected to the root " + model->getRoot()->name);
  std::map<std::string, int> index;
  for (const auto& l : order) index[l->name] = static_cast<int>(index.size());
  out.root = 0;

  // links that move: the child of a revolute or prismatic joint (a fixed child is merged into its parent)
  std::set<std::string> moving;
  for (const auto& kv : model->joints_) {
    const auto& j = kv.second;
    if (j && (j->type == urdf::Joint::REVOLUTE || j->type == urdf::Joint::CONTINUOUS || j->type == urdf::Joint::PRISMATIC))
      moving.insert(j->child_link_name);
  }
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
      // a link given an <inertial> that moves with a joint must have mass (Bullet divides by it; a
      // frame-only link has no <inertial> at all), and no manipulator link weighs a thousand tonnes
      if (ld.inertial.mass == 0.0 && moving.count(l->name))
        fail(origin, "link " + l->name + ": inertial mass: must be > 0 on a link moved by a joint (got 0; leave out <inertial> for a frame-only link)");
      if (ld.inertial.mass > kMaxLinkMassKg) {
        char got[32];
        std::snprintf(got, sizeof got, "%g", ld.inertial.mass);
        fail(origin, "link " + l->name + ": inertial mass: " + got + " kg is more than 1e6 kg (the Panda's links weigh 0.015-4.97 kg)");
      }
      if (!finite(o)) fail(origin, "link " + l->name + ": inertial origin is not finite");
      if (const std::string why = inertia_problem(in); !why.empty()) fail(origin, "link " + l->name + ": " + why);
    }
    for (const auto& c : l->collision_array) {
      if (!c || !c->geometry) continue;
      CollisionGeometry g;
      g.origin = to_iso(c->origin);
      if (!finite(g.origin)) fail(origin, "link " + l->name + ": collision origin is not finite");
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
          if (!s.allFinite() || !(s.cwiseAbs().minCoeff() > 0.0))
            fail(origin, "link " + l->name + ": mesh scale must be finite and non-zero");
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
      if (g.type != CollisionGeometry::Type::kMesh && !(g.size.allFinite() && g.size.minCoeff() >= 0.0 && g.size.x() > 0.0 &&
                                                        (g.type != CollisionGeometry::Type::kBox || g.size.minCoeff() > 0.0) &&
                                                        (g.type != CollisionGeometry::Type::kCylinder || g.size.y() > 0.0)))
        fail(origin, "link " + l->name + ": collision shape dimensions must be finite and positive");
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
      if (!finite(jd.origin)) fail(origin, "joint " + j->name + ": origin is not finite");
      switch (j->type) {
        case urdf::Joint::REVOLUTE: jd.type = JointDescription::Type::kRevolute; break;
        case urdf::Joint::CONTINUOUS: jd.type = JointDescription::Type::kContinuous; break;
        case urdf::Joint::PRISMATIC: jd.type = JointDescription::Type::kPrismatic; break;
        case urdf::Joint::FIXED: jd.type = JointDescription::Type::kFixed; break;
        default: fail(origin, "joint " + j->name + ": only fixed, revolute, continuous and prismatic joints are supported");
      }
      Eigen::Vector3d axis(j->axis.x, j->axis.y, j->axis.z);
      if (jd.movable()) {
        if (!axis.allFinite() || !(axis.norm() > 1e-12)) fail(origin, "joint " + j->name + ": zero or non-finite axis");
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
        if (!(jd.velocity >= 0.0) || !(jd.effort >= 0.0) || !std::isfinite(jd.velocity) || !std::isfinite(jd.effort))
          fail(origin, "joint " + j->name + ": limit velocity and effort must be finite and >= 0");
      }
      if (jd.type == JointDescription::Type::kRevolute || jd.type == JointDescription::Type::kPrismatic) {
        // urdfdom reads a missing lower/upper as 0, so <limit> without bounds arrives here as [0, 0]
        if (!j->limits) fail(origin, "joint " + j->name + ": a revolute or prismatic joint needs <limit>");
        if (!std::isfinite(jd.lower) || !std::isfinite(jd.upper))
          fail(origin, "joint " + j->name + ": limits must be finite");
        if (!(jd.lower < jd.upper))
          fail(origin, "joint " + j->name + ": limit lower (" + std::to_string(jd.lower) + ") must be below upper (" +
                           std::to_string(jd.upper) + "); a missing bound reads as 0, an empty range is a fixed joint");
      }
      if (j->dynamics) {
        jd.damping = j->dynamics->damping;
        if (!(jd.damping >= 0.0) || !std::isfinite(jd.damping)) fail(origin, "joint " + j->name + ": damping must be finite and >= 0");
      }
      if (j->mimic) {
        jd.mimic_joint = j->mimic->joint_name;
        jd.mimic_multiplier = j->mimic->multiplier;
        jd.mimic_offset = j->mimic->offset;
        if (!std::isfinite(jd.mimic_multiplier) || !std::isfinite(jd.mimic_offset))
          fail(origin, "joint " + j->name + ": mimic multiplier and offset must be finite");
        const auto target = model->joints_.find(*jd.mimic_joint);
        if (target == model->joints_.end() || !target->second || target->second->type == urdf::Joint::FIXED ||
            target->second->mimic || *jd.mimic_joint == j->name)
          fail(origin, "joint " + j->name + ": mimics '" + *jd.mimic_joint + "', which is not a movable, non-mimic joint");
      }
      out.joints.push_back(std::move(jd));
    }
  }
  return out;
}

RobotDescription load_urdf_file(const std::filesystem::path& urdf, const PackageMap& packages) {
  if (urdf.empty()) fail("--robot", "empty path (name a URDF file)");
  const std::string text = read_input_file(urdf.string(), "a URDF file", kMaxSmallFileBytes);
  const auto dir = std::filesystem::absolute(urdf).parent_path();
  return parse_urdf(text, dir, packages, urdf.string());
}

std::string_view panda_urdf_text() { return embedded::panda_urdf; }

const RobotDescription& panda_description() {
  static const RobotDescription panda = parse_urdf(embedded::panda_urdf, std::filesystem::path("."), {}, "<embedded panda.urdf>");
  return panda;
}

}  // namespace actionshift::sim
