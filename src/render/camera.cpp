// cameras: look-at view, perspective projection, per-task defaults, command-line parsing
#include "actionshift/render/camera.hpp"

#include "actionshift/core/error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>

namespace actionshift::render {

Eigen::Matrix4d Camera::view() const {
  const Eigen::Vector3d f = (target - eye).normalized();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  if (std::abs(f.dot(up)) > 0.999) up = Eigen::Vector3d::UnitX();  // looking straight down or up
  const Eigen::Vector3d s = f.cross(up).normalized();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Eigen::Matrix4d Camera::projection(double aspect) const {
  const double t = 1.0 / std::tan(0.5 * fovy);
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = t / aspect;
  p(1, 1) = t;
  p(2, 2) = (far_clip + near_clip) / (near_clip - far_clip);
  p(2, 3) = 2.0 * far_clip * near_clip / (near_clip - far_clip);
  p(3, 2) = -1.0;
  return p;
}

Eigen::Vector3d Camera::project(const Eigen::Vector3d& p, int width, int height) const {
  const Eigen::Vector4d e = view() * p.homogeneous();
  const Eigen::Vector4d c = projection(static_cast<double>(width) / height) * e;
  const double x = (c.x() / c.w() + 1.0) * 0.5 * width;
  const double y = (1.0 - c.y() / c.w()) * 0.5 * height;
  return {x, y, -e.z()};
}

Camera default_camera(sim::TaskId task) {
  Camera c;
  if (const auto& view = sim::task_description(task).camera) {
    c.eye = view->eye;
    c.target = view->target;
  }
  return c;
}

const std::vector<std::string>& camera_names() {
  static const std::vector<std::string> names{"default", "front", "side", "top"};
  return names;
}

namespace {

[[noreturn]] void bad_camera(std::string_view spec, const std::string& why) {
  throw InputError("command line", "--camera", "'" + std::string(spec) + "' " + why +
                                                   " (default, front, side, top, or EX,EY,EZ,TX,TY,TZ[,FOV_DEG])");
}

}  // namespace

Camera parse_camera(std::string_view spec, sim::TaskId task) {
  Camera c = default_camera(task);
  if (spec == "default" || spec.empty()) return c;
  if (spec == "front") {
    c.eye = Eigen::Vector3d(1.1, 0.0, 0.45);
    c.target = Eigen::Vector3d(0.0, 0.0, 0.15);
    return c;
  }
  if (spec == "side") {
    c.eye = Eigen::Vector3d(-0.1, -1.1, 0.45);
    c.target = Eigen::Vector3d(-0.1, 0.0, 0.15);
    return c;
  }
  if (spec == "top") {
    c.eye = Eigen::Vector3d(-0.05, 0.0, 1.4);
    c.target = Eigen::Vector3d(-0.05, 0.0, 0.0);
    return c;
  }
  if (spec.find(',') == std::string_view::npos) bad_camera(spec, "is not a camera");
  std::vector<double> v;
  std::size_t pos = 0;
  while (pos <= spec.size()) {
    const std::size_t end = std::min(spec.find(',', pos), spec.size());
    const std::string_view item = spec.substr(pos, end - pos);
    double x = 0.0;
    const auto r = std::from_chars(item.data(), item.data() + item.size(), x);
    if (item.empty() || r.ec != std::errc() || r.ptr != item.data() + item.size() || !std::isfinite(x))
      bad_camera(spec, "has a non-number '" + std::string(item) + "'");
    v.push_back(x);
    pos = end + 1;
  }
  if (v.size() != 6 && v.size() != 7) bad_camera(spec, "has " + std::to_string(v.size()) + " numbers, 6 or 7 expected");
  c.eye = Eigen::Vector3d(v[0], v[1], v[2]);
  c.target = Eigen::Vector3d(v[3], v[4], v[5]);
  if ((c.eye - c.target).norm() < 1e-6) bad_camera(spec, "has the eye at the target");
  if (v.size() == 7) {
    if (!(v[6] > 1.0 && v[6] < 170.0)) bad_camera(spec, "has a field of view outside (1, 170) degrees");
    c.fovy = v[6] * std::numbers::pi / 180.0;
  }
  return c;
}

}  // namespace actionshift::render
