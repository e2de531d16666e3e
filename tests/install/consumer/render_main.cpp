// Renders one box with an installed ActionShift::render (OSMesa is opened at the first render, not
// linked) and checks the pixel at the box's centre has the box's colour and a corner the background.
#include <actionshift/render/camera.hpp>
#include <actionshift/render/renderer.hpp>
#include <actionshift/sim/scene.hpp>

#include <iostream>

int main() {
  using namespace actionshift;
  sim::Scene scene;
  sim::SceneShape box;
  box.size = Eigen::Vector3d(0.2, 0.2, 0.2);
  box.pose.translation() = Eigen::Vector3d(0.0, 0.0, 0.35);
  box.rgba = sim::kCubeColor;
  scene.shapes.push_back(box);
  render::Renderer r(64, 48);
  const render::Image img = r.render(scene, render::Camera{});
  const auto centre = img.at(32, 24), corner = img.at(0, 0);
  std::cout << "render centre " << int(centre.r) << "," << int(centre.g) << "," << int(centre.b) << " corner "
            << int(corner.r) << "," << int(corner.g) << "," << int(corner.b) << "\n";
  const bool red = centre.r > 2 * centre.g && centre.r > 2 * centre.b;
  const bool sky = corner.b > corner.r && corner.b > 200;
  return red && sky ? 0 : 1;
}
