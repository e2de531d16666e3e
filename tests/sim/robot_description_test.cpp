// urdf loading: the embedded panda, meshes through assimp, path resolution, clear errors
#include "actionshift/sim/robot_description.hpp"

#include "actionshift/core/error.hpp"

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
  EXPECT_THROW(p.link_index("nope"), std::out_of_range);
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

}  // namespace
}  // namespace actionshift::sim
