// scene snapshots, cameras, the OSMesa renderer and image files
#include "actionshift/core/error.hpp"
#include "actionshift/render/camera.hpp"
#include "actionshift/render/image.hpp"
#include "actionshift/render/renderer.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/scene.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace actionshift::render {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using sim::ScenePart;

bool reddish(Rgb c) { return c.r > 110 && c.r > 2 * c.g && c.r > 2 * c.b; }

fs::path temp_file(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("actionshift_render_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

sim::Env reset_env(sim::TaskId task, std::uint64_t seed) {
  sim::Env env(sim::EnvModel::make(task));
  env.reset(seed);
  return env;
}

TEST(Scene, HoldsTheRobotTableObjectsAndGoalAtTheEnvironmentsPoses) {
  const sim::Env env = reset_env(sim::TaskId::kPickCube, 7);
  const sim::Scene scene = sim::scene_of(env);
  const sim::TaskSnapshot snap = env.snapshot();
  int robot = 0, objects = 0, goals = 0, tables = 0;
  for (const auto& s : scene.shapes) {
    robot += s.part == ScenePart::kRobot;
    tables += s.part == ScenePart::kTable;
    if (s.part == ScenePart::kObject) {
      ++objects;
      EXPECT_TRUE(s.pose.isApprox(snap.obj[0]));
      // the cube rests on the table: its half height is its centre height
      EXPECT_NEAR(0.5 * s.size.z(), snap.obj[0].translation().z(), 1e-3);
    }
    if (s.part == ScenePart::kGoal) {
      ++goals;
      EXPECT_TRUE(s.pose.translation().isApprox(snap.goal));
    }
  }
  std::size_t collisions = 0;
  for (const auto& l : env.model().robot().links) collisions += l.collisions.size();
  EXPECT_EQ(robot, static_cast<int>(collisions));
  EXPECT_EQ(objects, 1);
  EXPECT_EQ(goals, 1);
  EXPECT_EQ(tables, 1);
}

TEST(Scene, RobotShapesFollowTheJointsAndStackPegHaveTheirObjects) {
  sim::Env env(sim::EnvModel::make(sim::TaskId::kPickCube));
  env.reset(3);
  const sim::Scene before = sim::scene_of(env);
  for (int i = 0; i < 5; ++i) env.step(std::vector<double>{0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0});
  const sim::Scene after = sim::scene_of(env);
  ASSERT_EQ(before.shapes.size(), after.shapes.size());
  double moved = 0.0;
  for (std::size_t i = 0; i < before.shapes.size(); ++i)
    if (before.shapes[i].part == ScenePart::kRobot)
      moved = std::max(moved, (before.shapes[i].pose.translation() - after.shapes[i].pose.translation()).norm());
  EXPECT_GT(moved, 0.01);  // the hand went up

  auto count_objects = [](const sim::Scene& s) {
    return std::count_if(s.shapes.begin(), s.shapes.end(), [](const auto& x) { return x.part == ScenePart::kObject; });
  };
  EXPECT_EQ(count_objects(sim::scene_of(reset_env(sim::TaskId::kStackCube, 1))), 2);
  EXPECT_EQ(count_objects(sim::scene_of(reset_env(sim::TaskId::kPegInsertionSide, 1))), 2 + 4);  // peg halves + 4 box walls
}

TEST(Camera, ProjectsTheTargetToTheImageCentreAndParsesSpecs) {
  const Camera c = default_camera(sim::TaskId::kPickCube);
  const Eigen::Vector3d p = c.project(c.target, 320, 240);
  EXPECT_NEAR(p.x(), 160.0, 1e-9);
  EXPECT_NEAR(p.y(), 120.0, 1e-9);
  EXPECT_NEAR(p.z(), (c.eye - c.target).norm(), 1e-9);
  // a point above the target is higher in the image (smaller y)
  EXPECT_LT(c.project(c.target + Eigen::Vector3d(0, 0, 0.1), 320, 240).y(), 120.0);

  const Camera custom = parse_camera("1,2,3,0,0,0.5,40", sim::TaskId::kPushCube);
  EXPECT_EQ(custom.eye, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(custom.target, Eigen::Vector3d(0, 0, 0.5));
  EXPECT_NEAR(custom.fovy, 40.0 * std::numbers::pi / 180.0, 1e-12);
  EXPECT_EQ(parse_camera("default", sim::TaskId::kPegInsertionSide).eye, Eigen::Vector3d(0.5, -0.5, 0.8));
  for (const auto& name : camera_names()) EXPECT_NO_THROW(parse_camera(name, sim::TaskId::kPickCube));
  for (const char* bad : {"fisheye", "1,2,3", "1,2,3,4,5,x", "0,0,0,0,0,0", "1,2,3,0,0,0,200"})
    EXPECT_THAT([&] { parse_camera(bad, sim::TaskId::kPickCube); },
                ::testing::ThrowsMessage<InputError>(HasSubstr("command line: --camera: '")))
        << bad;
}

TEST(Renderer, DrawsTheCubeInItsColourAtItsProjectedPixel) {
  const sim::Env env = reset_env(sim::TaskId::kPickCube, 11);
  const sim::Scene scene = sim::scene_of(env);
  const Camera cam = default_camera(sim::TaskId::kPickCube);
  Renderer r(320, 240);
  const Image im = r.render(scene, cam);
  ASSERT_EQ(im.width(), 320);
  ASSERT_EQ(im.height(), 240);
  // the centre of the cube's top face
  const Eigen::Vector3d top = env.snapshot().obj[0].translation() + Eigen::Vector3d(0, 0, sim::kSceneCubeHalf);
  const Eigen::Vector3d px = cam.project(top, 320, 240);
  const int x = static_cast<int>(px.x()), y = static_cast<int>(px.y());
  ASSERT_TRUE(x >= 0 && x < 320 && y >= 0 && y < 240);
  const Rgb c = im.at(x, y);
  EXPECT_TRUE(reddish(c)) << int(c.r) << "," << int(c.g) << "," << int(c.b);

  // without the cube the same pixel is not the cube's colour (it shows the table)
  sim::Scene no_cube = scene;
  std::erase_if(no_cube.shapes, [](const sim::SceneShape& s) { return s.part == ScenePart::kObject; });
  const Rgb t = r.render(no_cube, cam).at(x, y);
  EXPECT_FALSE(reddish(t)) << int(t.r) << "," << int(t.g) << "," << int(t.b);

  // the robot is drawn: the hand's pixel is a dark grey, not the background
  int robot_pixels = 0;
  const Rgb bg = r.render(sim::Scene{}, cam).at(0, 0);
  for (const auto& s : scene.shapes) {
    if (s.part != ScenePart::kRobot) continue;
    const Eigen::Vector3d q = cam.project(s.pose.translation(), 320, 240);
    const Rgb rc = im.at(std::clamp(static_cast<int>(q.x()), 0, 319), std::clamp(static_cast<int>(q.y()), 0, 239));
    if (!(rc == bg) && std::abs(rc.r - rc.g) < 20 && std::abs(rc.g - rc.b) < 20) ++robot_pixels;
  }
  EXPECT_GE(robot_pixels, 5);
}

TEST(Renderer, RejectsBadSizes) {
  EXPECT_THROW(Renderer(0, 10), std::invalid_argument);
  EXPECT_THROW(Renderer(10, 5000), std::invalid_argument);
}

TEST(Images, GifRoundTripsFramesAndPngIsWritten) {
  std::vector<Image> frames;
  for (int k = 0; k < 3; ++k) {
    Image im(40, 30, {20, 40, 60});
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 10; ++x) im.set(5 + 10 * k + x, 10 + y, {230, 20, 20});
    draw_text(im, 1, 1, "step 1", {255, 255, 255});
    frames.push_back(im);
  }
  const fs::path gif = temp_file("frames.gif");
  write_gif(gif, frames, 5);
  const std::vector<Image> back = read_gif(gif);
  ASSERT_EQ(back.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(reddish(back[static_cast<std::size_t>(k)].at(10 + 10 * k, 15)));
    const Rgb bg = back[static_cast<std::size_t>(k)].at(39, 29);
    EXPECT_NEAR(bg.b, 60, 8);
  }
  EXPECT_FALSE(reddish(back[0].at(30, 15)));  // the square moved
  const Rgb s = back[0].at(2, 1);  // the 's' of the overlay text; giflib quantises to 5 bits a channel
  EXPECT_TRUE(s.r >= 240 && s.g >= 240 && s.b >= 240) << int(s.r) << "," << int(s.g) << "," << int(s.b);

  const fs::path png = temp_file("frame.png");
  write_png(png, frames[0]);
  std::ifstream f(png, std::ios::binary);
  char sig[8] = {};
  f.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");

  EXPECT_THAT([&] { write_png("/nonexistent-dir/x.png", frames[0]); }, ::testing::ThrowsMessage<InputError>(HasSubstr("/nonexistent-dir/x.png: out: cannot write file")));
  EXPECT_THAT([&] { write_gif("/nonexistent-dir/x.gif", frames); }, ::testing::ThrowsMessage<InputError>(HasSubstr("/nonexistent-dir/x.gif: out: cannot write file")));

  const Image wide = side_by_side({frames[0], frames[1]}, 4);
  EXPECT_EQ(wide.width(), 84);
  EXPECT_EQ(wide.at(41, 0), (Rgb{255, 255, 255}));
  EXPECT_TRUE(reddish(wide.at(44 + 20, 15)));
}

}  // namespace
}  // namespace actionshift::render
