// urdf loading: the embedded panda, meshes through assimp, path resolution, clear errors
#include "actionshift/sim/robot_description.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/sim/kinematics.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace actionshift::sim {
namespace {

using ::testing::HasSubstr;

TEST(PandaDescription, ChainLimitsAndMasses) {
  const RobotDescription& p = panda_description();
  EXPECT_EQ(p.name, "panda");
  EXPECT_EQ(p.links[static_cast<std::size_t>(p.root)].name, "panda_link0");
  int movable = 0;
  for (const auto& j : p.joints) movable += j.movable() ? 1 : 0;
  EXPECT_EQ(movable, 9);
  const auto& j4 = p.joints[static_cast<std::size_t>(p.joint_index("panda_joint4"))];
  EXPECT_DOUBLE_EQ(j4.lower, -3.0718);
  EXPECT_DOUBLE_EQ(j4.upper, -0.0698);
  const auto& f2 = p.joints[static_cast<std::size_t>(p.joint_index("panda_finger_joint2"))];
  ASSERT_TRUE(f2.mimic_joint.has_value());
  EXPECT_EQ(*f2.mimic_joint, "panda_finger_joint1");
  EXPECT_TRUE(f2.axis.isApprox(Eigen::Vector3d(0, -1, 0)));
  double mass = 0;
  for (const auto& l : p.links) mass += l.inertial.mass;
  EXPECT_NEAR(mass, 17.45, 0.01);  // total of the published identified inertial set (docs/reference.md, Panda and tasks)
  // four collision boxes per finger
  EXPECT_EQ(p.links[static_cast<std::size_t>(p.link_index("panda_leftfinger"))].collisions.size(), 4u);
  EXPECT_THAT([&] { p.link_index("nope"); }, ::testing::ThrowsMessage<InputError>(HasSubstr("no link named 'nope'")));
  EXPECT_THAT([&] { p.joint_index("nope"); }, ::testing::ThrowsMessage<InputError>(HasSubstr("no joint named 'nope'")));
}

class UrdfFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("actionshift_urdf_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                                     "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_ / "meshes");
    std::filesystem::create_directories(dir_ / "pkg" / "shapes");
    write(dir_ / "meshes" / "box.obj", obj_box(0.02));
    write(dir_ / "pkg" / "shapes" / "box.obj", obj_box(0.05));
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  static std::string obj_box(double h) {
    std::string s;
    for (int i = 0; i < 8; ++i)
      s += "v " + std::to_string((i & 1) ? h : -h) + " " + std::to_string((i & 2) ? h : -h) + " " + std::to_string((i & 4) ? h : -h) + "\n";
    s += "f 1 2 4 3\nf 5 6 8 7\nf 1 2 6 5\nf 3 4 8 7\nf 1 3 7 5\nf 2 4 8 6\n";
    return s;
  }
  static void write(const std::filesystem::path& p, const std::string& text) { std::ofstream(p) << text; }
  std::string urdf(const std::string& mesh_a, const std::string& mesh_b) const {
    return R"(<robot name="toy">
  <link name="base"><collision><geometry><mesh filename=")" + mesh_a + R"(" scale="2 2 2"/></geometry></collision></link>
  <link name="arm"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><mesh filename=")" + mesh_b + R"("/></geometry></collision></link>
  <link name="tip"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="arm"/><child link="tip"/><origin xyz="0 0 0.2"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.1" effort="10" velocity="1"/><mimic joint="j1" multiplier="0.5"/></joint>
</robot>)";
  }
  std::filesystem::path dir_;
};

TEST_F(UrdfFiles, LoadsObjMeshesThroughRelativePackageAndFileUris) {
  write(dir_ / "toy.urdf", urdf("meshes/box.obj", "package://shapes_pkg/shapes/box.obj"));
  const RobotDescription d = load_urdf_file(dir_ / "toy.urdf", {{"shapes_pkg", dir_ / "pkg"}});
  ASSERT_EQ(d.links.size(), 3u);
  const auto& base = d.links[static_cast<std::size_t>(d.link_index("base"))].collisions.at(0);
  ASSERT_EQ(base.type, CollisionGeometry::Type::kMesh);
  ASSERT_EQ(base.mesh->vertices.size(), 8u);
  double maxc = 0;
  for (const auto& v : base.mesh->vertices) maxc = std::max(maxc, v.cwiseAbs().maxCoeff());
  EXPECT_NEAR(maxc, 0.04, 1e-9);  // 0.02 half size, scale 2
  const auto& arm = d.links[static_cast<std::size_t>(d.link_index("arm"))].collisions.at(0);
  maxc = 0;
  for (const auto& v : arm.mesh->vertices) maxc = std::max(maxc, v.cwiseAbs().maxCoeff());
  EXPECT_NEAR(maxc, 0.05, 1e-9);
  EXPECT_NEAR(arm.origin.translation().z(), 0.1, 1e-12);
  const auto& j2 = d.joints[static_cast<std::size_t>(d.joint_index("j2"))];
  EXPECT_EQ(j2.type, JointDescription::Type::kPrismatic);
  EXPECT_EQ(*j2.mimic_joint, "j1");
  EXPECT_DOUBLE_EQ(j2.mimic_multiplier, 0.5);

  write(dir_ / "abs.urdf", urdf("file://" + (dir_ / "meshes" / "box.obj").string(), "meshes/box.obj"));
  EXPECT_NO_THROW(load_urdf_file(dir_ / "abs.urdf"));
}

TEST_F(UrdfFiles, MissingMeshIsAClearError) {
  write(dir_ / "bad.urdf", urdf("meshes/box.obj", "meshes/missing.obj"));
  try {
    load_urdf_file(dir_ / "bad.urdf");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad.urdf"));
    EXPECT_THAT(e.what(), HasSubstr("missing.obj"));
  }
}

TEST_F(UrdfFiles, UnreadableMeshAndUnknownPackageAndBadXml) {
  write(dir_ / "meshes" / "junk.obj", "this is not a mesh\n");
  write(dir_ / "junk.urdf", urdf("meshes/junk.obj", "meshes/box.obj"));
  EXPECT_THAT([&] { load_urdf_file(dir_ / "junk.urdf"); }, ::testing::ThrowsMessage<InputError>(HasSubstr("junk.obj")));
  write(dir_ / "pkg.urdf", urdf("package://nowhere/box.obj", "meshes/box.obj"));
  EXPECT_THAT([&] { load_urdf_file(dir_ / "pkg.urdf"); }, ::testing::ThrowsMessage<InputError>(HasSubstr("nowhere")));
  write(dir_ / "xml.urdf", "<robot name='x'><link name='a'>");
  EXPECT_THAT([&] { load_urdf_file(dir_ / "xml.urdf"); }, ::testing::ThrowsMessage<InputError>(HasSubstr("xml.urdf")));
  EXPECT_THAT([&] { load_urdf_file(dir_ / "does_not_exist.urdf"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("does_not_exist.urdf")));
}

// ---- hostile robot descriptions: every one is a one-line InputError naming the file, never a crash

std::string panda_with(const std::string& before, const std::string& after) {
  std::string text(panda_urdf_text());
  const auto at = text.find(before);
  EXPECT_NE(at, std::string::npos) << before;
  if (at != std::string::npos) text.replace(at, before.size(), after);
  return text;
}

std::string rejection(const std::string& xml) {
  try {
    parse_urdf(xml, ".", {}, "hostile.urdf");
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.rfind("hostile.urdf: ", 0), 0u) << what;
    return what;
  }
  ADD_FAILURE() << "accepted";
  return {};
}

TEST(HostileUrdf, KinematicLoopIsRejectedNotARecursionOverflow) {
  const std::string loop = panda_with("</robot>", R"(<joint name="loop" type="fixed"><parent link="panda_link7"/><child link="panda_link1"/></joint></robot>)");
  EXPECT_THAT(rejection(loop), HasSubstr("kinematic loop"));
}

TEST(HostileUrdf, ASecondParentIsRejectedBeforeUrdfdomBuildsItsTree) {
  // found by the urdf fuzz target: the last arm joint names panda_link4 as its child, so link 4 has two
  // parents and panda_link7 becomes a second root; urdfdom rejected that only after linking the cycle,
  // which it never freed (the sanitizer run of this test reports any leak)
  const std::string two_parents = panda_with(R"(<parent link="panda_link6"/><child link="panda_link7"/>)",
                                             R"(<parent link="panda_link6"/><child link="panda_link4"/>)");
  EXPECT_THAT(rejection(two_parents), HasSubstr("link panda_link4: child of two joints (panda_joint4 and panda_joint7)"));
  // a cycle in which every link has one parent (and no root at all)
  EXPECT_THAT(rejection(R"(<robot name="r"><link name="a"/><link name="b"/>
    <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
    <joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint></robot>)"),
              HasSubstr("joints form a kinematic loop through link"));
}

TEST(HostileUrdf, UrdfdomsOwnReasonIsInTheMessage) {
  // a revolute joint without <limit>: urdfdom refuses it and says why
  const std::string no_limit = panda_with(R"(<limit lower="-2.8973" upper="2.8973" velocity="2.1750" effort="87"/><dynamics damping="0.003"/>
  </joint>
  <joint name="panda_joint2")", R"(</joint>
  <joint name="panda_joint2")");
  EXPECT_THAT(rejection(no_limit), HasSubstr("limits"));
  EXPECT_THAT(rejection(panda_with(R"(<child link="panda_link2"/>)", R"(<child link="panda_link_nowhere"/>)")),
              HasSubstr("panda_link_nowhere"));
  EXPECT_THAT(rejection(panda_with("</robot>", R"(<link name="island"/></robot>)")), HasSubstr("root"));
  const std::string truncated(panda_urdf_text().substr(0, panda_urdf_text().size() / 2));
  EXPECT_THAT(rejection(truncated), HasSubstr("not a valid URDF: "));
  EXPECT_THAT(rejection(truncated), ::testing::Not(HasSubstr("urdfdom could not parse it")));
}

TEST(HostileUrdf, NonFiniteOriginIsRejected) {
  EXPECT_THAT(rejection(panda_with(R"(<parent link="panda_link0"/><child link="panda_link1"/>)",
                                   R"(<parent link="panda_link0"/><child link="panda_link1"/><origin xyz="0 nan 0"/>)")),
              ::testing::AnyOf(HasSubstr("origin"), HasSubstr("nan")));
}

TEST(HostileUrdf, NonFiniteMassInertiaAndShapeSizesAreRejected) {
  // urdfdom logs these and returns the link without its inertial or collisions: they loaded and ran
  // (a NaN box changed the episodes) until a logged error became a rejection
  EXPECT_THAT(rejection(panda_with(R"(<mass value="4.970684"/>)", R"(<mass value="nan"/>)")), HasSubstr("panda_link1"));
  EXPECT_THAT(rejection(panda_with(R"(<mass value="4.970684"/>)", R"(<mass value="inf"/>)")), HasSubstr("panda_link1"));
  EXPECT_THAT(rejection(panda_with(R"(ixx="0.70337")", R"(ixx="nan")")), HasSubstr("panda_link1"));
  EXPECT_THAT(rejection(panda_with(R"(<sphere radius="0.06"/>)", R"(<sphere radius="nan"/>)")), HasSubstr("radius [nan]"));
  EXPECT_THAT(rejection(panda_with(R"(<cylinder radius="0.06" length="0.283"/>)", R"(<cylinder radius="0.06" length="inf"/>)")),
              HasSubstr("panda_link1"));
}

TEST(HostileUrdf, PhysicallyInvalidLimitsAndInertiasAreRejected) {
  EXPECT_THAT(rejection(panda_with(R"(lower="-3.0718" upper="-0.0698")", R"(lower="-0.0698" upper="-3.0718")")),
              HasSubstr("panda_joint4: limit lower"));
  // <limit> without bounds: urdfdom defaults both to 0
  EXPECT_THAT(rejection(panda_with(R"(lower="-3.0718" upper="-0.0698" )", "")), HasSubstr("panda_joint4: limit lower"));
  EXPECT_THAT(rejection(panda_with(R"(velocity="2.1750" effort="87"/>)", R"(velocity="-1" effort="87"/>)")), HasSubstr("velocity"));
  const std::string toy = R"(<robot name="toy"><link name="a"/><link name="b"><inertial><mass value="1"/>
    <inertia ixx="INERTIA" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
    <joint name="j" type="revolute"><parent link="a"/><child link="b"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";
  const auto with_ixx = [&](const std::string& v) { std::string t = toy; t.replace(t.find("INERTIA"), 7, v); return t; };
  EXPECT_NO_THROW(parse_urdf(with_ixx("0.01"), "."));
  EXPECT_THAT(rejection(with_ixx("-0.01")), HasSubstr("link b: inertia is not positive semi-definite"));
  EXPECT_THAT(rejection(with_ixx("0.05")), HasSubstr("triangle inequality"));
  std::string mass = with_ixx("0.01");
  mass.replace(mass.find(R"(value="1")"), 9, R"(value="-1")");
  EXPECT_THAT(rejection(mass), HasSubstr("mass"));
}

TEST(HostileUrdf, MasslessOrAbsurdlyHeavyMovingLinksAreRejected) {
  // a moving link with an explicit zero mass, and a 1e30 kg link, were accepted
  EXPECT_THAT(rejection(panda_with(R"(<mass value="4.970684"/>)", R"(<mass value="0"/>)")),
              HasSubstr("link panda_link1: inertial mass: must be > 0 on a link moved by a joint"));
  EXPECT_THAT(rejection(panda_with(R"(<mass value="4.970684"/>)", R"(<mass value="1e30"/>)")),
              HasSubstr("link panda_link1: inertial mass: 1e+30 kg is more than 1e6 kg"));
  // the fixed root may be massless (it does not move), and a frame-only moving link has no <inertial>
  EXPECT_NO_THROW(parse_urdf(panda_with(R"(<mass value="0.629769"/>)", R"(<mass value="0"/>)"), "."));
}

TEST(HostileUrdf, LongMeshNamesAreCutInMessages) {
  const std::string toy = R"(<robot name="toy"><link name="a"><collision><geometry><mesh filename="NAME"/></geometry></collision></link></robot>)";
  const auto with_name = [&](const std::string& v) { std::string t = toy; t.replace(t.find("NAME"), 4, v); return t; };
  const std::string missing = rejection(with_name("meshes/" + std::string(100000, 'm') + ".stl"));
  EXPECT_THAT(missing, HasSubstr("mesh file not found: '"));
  EXPECT_THAT(missing, HasSubstr("more bytes)"));
  EXPECT_LT(missing.size(), 600u);
  const std::string package = rejection(with_name("package://" + std::string(100000, 'p') + "/a.stl"));
  EXPECT_THAT(package, HasSubstr("not in the package map (give --package NAME=DIR)"));
  EXPECT_LT(package.size(), 600u);
}

TEST(HostileUrdf, DeepXmlAndUnknownMimicAreRejected) {
  std::string deep = "<robot name='x'>";
  for (int i = 0; i < 100000; ++i) deep += "<a>";
  EXPECT_THAT(rejection(deep), HasSubstr("nested deeper"));
  EXPECT_THAT(rejection(panda_with(R"(<mimic joint="panda_finger_joint1")", R"(<mimic joint="panda_ghost")")), HasSubstr("panda_ghost"));
}

TEST(HostileUrdf, MissingTcpLinkIsTheProjectsInputError) {
  EXPECT_THAT([] { KinematicChain(panda_description(), "panda_tcp_nowhere"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("panda_tcp_nowhere")));
}

TEST_F(UrdfFiles, ColladaMeshHasTheBoundsOfItsStlTwin) {
  // one asymmetric tetrahedron, written as binary-free ASCII STL and as a Z_UP Collada file
  const double v[4][3] = {{0.0, 0.0, 0.0}, {0.1, 0.0, 0.0}, {0.0, 0.2, 0.0}, {0.0, 0.0, 0.3}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string stl = "solid t\n";
  for (const auto& t : f) {
    stl += "facet normal 0 0 0\nouter loop\n";
    for (int k : t) stl += "vertex " + std::to_string(v[k][0]) + " " + std::to_string(v[k][1]) + " " + std::to_string(v[k][2]) + "\n";
    stl += "endloop\nendfacet\n";
  }
  stl += "endsolid t\n";
  write(dir_ / "meshes" / "t.stl", stl);
  std::string pos, idx;
  for (const auto& p : v) pos += std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + " ";
  for (const auto& t : f) idx += std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + " ";
  write(dir_ / "meshes" / "t.dae", R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="g" name="g"><mesh>
    <source id="g-pos"><float_array id="g-pos-array" count="12">)" + pos + R"(</float_array>
      <technique_common><accessor source="#g-pos-array" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="g-vtx"><input semantic="POSITION" source="#g-pos"/></vertices>
    <triangles count="4"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>)" + idx + R"(</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n" name="n"><instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
)");
  const auto bounds = [&](const std::string& mesh) {
    write(dir_ / "m.urdf", urdf(mesh, "meshes/box.obj"));
    const RobotDescription d = load_urdf_file(dir_ / "m.urdf");
    const auto& g = d.links[static_cast<std::size_t>(d.link_index("base"))].collisions.at(0);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
    for (const auto& p : g.mesh->vertices) { lo = lo.cwiseMin(p); hi = hi.cwiseMax(p); }
    return std::pair{lo, hi};
  };
  const auto [stl_lo, stl_hi] = bounds("meshes/t.stl");
  const auto [dae_lo, dae_hi] = bounds("meshes/t.dae");
  EXPECT_TRUE(stl_hi.isApprox(Eigen::Vector3d(0.2, 0.4, 0.6), 1e-6)) << stl_hi.transpose();  // scale 2
  EXPECT_TRUE(dae_lo.isApprox(stl_lo, 1e-6) || (dae_lo - stl_lo).norm() < 1e-9) << dae_lo.transpose() << " vs " << stl_lo.transpose();
  EXPECT_TRUE(dae_hi.isApprox(stl_hi, 1e-6)) << dae_hi.transpose() << " vs " << stl_hi.transpose();
}

}  // namespace
}  // namespace actionshift::sim
