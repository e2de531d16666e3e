#pragma once
/// \file
/// Headless OpenGL rendering of a sim::Scene with OSMesa (Mesa's off-screen software renderer,
/// llvmpipe): no display, no GPU, no X libraries. Lit, flat-coloured primitives: boxes, spheres,
/// cylinders, and the convex hull of mesh vertices (what Bullet collides with).

#include "actionshift/render/camera.hpp"
#include "actionshift/render/image.hpp"
#include "actionshift/sim/scene.hpp"

#include <memory>

namespace actionshift::render {

/// One off-screen GL context with a width x height colour and depth buffer. Not thread-safe: use one
/// Renderer per thread. Construction takes a few milliseconds; reuse it for every frame.
class Renderer {
 public:
  /// Throws std::invalid_argument for a size outside [1, 4096], std::runtime_error if OSMesa cannot
  /// create a context.
  Renderer(int width, int height);
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;

  int width() const;
  int height() const;
  /// Draw `scene` seen from `camera`.
  Image render(const sim::Scene& scene, const Camera& camera);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace actionshift::render
