#pragma once
/// \file
/// Pinhole cameras: the per-task default (ManiSkill's human-render camera), named alternatives and
/// custom eye/target cameras, with the projection the renderer uses.

#include "actionshift/sim/task.hpp"

#include <Eigen/Core>

#include <string>
#include <string_view>
#include <vector>

namespace actionshift::render {

/// A look-at camera. World frame, z up.
struct Camera {
  Eigen::Vector3d eye{0.6, 0.7, 0.6};     ///< [m] camera position
  Eigen::Vector3d target{0.0, 0.0, 0.35};  ///< [m] point at the image centre
  double fovy{1.0};                        ///< [rad] vertical field of view
  double near_clip{0.01}, far_clip{100.0};  ///< [m]

  /// OpenGL view matrix (world -> eye, looking down -z, z world-up projected to image-up).
  Eigen::Matrix4d view() const;
  /// OpenGL perspective projection for an image of this aspect ratio (width / height).
  Eigen::Matrix4d projection(double aspect) const;
  /// Pixel coordinates (x right, y down, origin top-left, pixel centres at +0.5) of world point `p`
  /// in a width x height image; the third entry is the depth in front of the camera [m] (<= 0: behind).
  Eigen::Vector3d project(const Eigen::Vector3d& p, int width, int height) const;
};

/// The task's default camera: ManiSkill's human-render camera (eye (0.6, 0.7, 0.6) looking at
/// (0, 0, 0.35), fov 1 rad; PegInsertionSide: eye (0.5, -0.5, 0.8) looking at (0.05, -0.1, 0.4)).
Camera default_camera(sim::TaskId task);

/// Names accepted by parse_camera besides a custom list of numbers.
const std::vector<std::string>& camera_names();

/// A camera from a command-line value: `default` (the task's), `front` (from +x), `side` (from -y),
/// `top` (from above), or `EX,EY,EZ,TX,TY,TZ[,FOV_DEG]` (eye, target, vertical field of view in degrees,
/// default 57.3). Throws actionshift::InputError("command line", "--camera", reason) otherwise.
Camera parse_camera(std::string_view spec, sim::TaskId task);

}  // namespace actionshift::render
