// The only translation unit that includes OSMesa / OpenGL: a fixed-function GL scene renderer.
//
// libOSMesa is opened with dlopen(3) when the first Renderer is made, not linked: it pulls in
// llvmpipe's libLLVM (about 100 MB, half a million relocations), which would otherwise cost every
// start of every program linking ActionShift::render (the CLI: about 60 ms of its 90) although
// only rendering uses it (docs/results/benchmarks.md, "Command-line start-up").
#include "actionshift/render/renderer.hpp"

#include <GL/osmesa.h>
#include <GL/gl.h>

#include <dlfcn.h>

#include <LinearMath/btConvexHullComputer.h>

#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

namespace actionshift::render {

namespace {

// every OSMesa and GL entry point this file calls
#define ACTIONSHIFT_GL_FUNCTIONS(X) \
  X(OSMesaCreateContextExt) X(OSMesaDestroyContext) X(OSMesaMakeCurrent) \
  X(glBegin) X(glBlendFunc) X(glClear) X(glClearColor) X(glColor4f) X(glColorMaterial) \
  X(glDepthMask) X(glDisable) X(glEnable) X(glEnd) X(glFinish) X(glLightModelfv) \
  X(glLightModeli) X(glLightfv) X(glLoadMatrixd) X(glMatrixMode) X(glMultMatrixd) X(glNormal3f) \
  X(glNormal3fv) X(glPopMatrix) X(glPushMatrix) X(glScaled) X(glShadeModel) X(glVertex3f) \
  X(glVertex3fv) X(glViewport)

struct GlApi {
#define ACTIONSHIFT_GL_POINTER(name) decltype(&::name) name{nullptr};
  ACTIONSHIFT_GL_FUNCTIONS(ACTIONSHIFT_GL_POINTER)
#undef ACTIONSHIFT_GL_POINTER
};

// libOSMesa's soname on Debian 12 (libosmesa6), then the development symlink
constexpr const char* kOsmesaLibraries[] = {"libOSMesa.so.8", "libOSMesa.so"};

GlApi load_gl_api() {
  void* lib = nullptr;
  std::string why;
  for (const char* name : kOsmesaLibraries) {
    lib = ::dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (lib != nullptr) break;
    const char* e = ::dlerror();
    if (why.empty() && e != nullptr) why = e;
  }
  if (lib == nullptr)
    throw std::runtime_error("rendering needs OSMesa, which could not be loaded (" + why +
                             "); install it with: apt-get install libosmesa6");
  GlApi api;  // the library stays loaded for the life of the process
#define ACTIONSHIFT_GL_LOAD(name)                                                                    \
  api.name = reinterpret_cast<decltype(api.name)>(::dlsym(lib, #name));                            \
  if (api.name == nullptr) throw std::runtime_error("OSMesa library lacks the function " #name);
  ACTIONSHIFT_GL_FUNCTIONS(ACTIONSHIFT_GL_LOAD)
#undef ACTIONSHIFT_GL_LOAD
  return api;
}

// loaded once per process, on first use (a failed load is retried by the next call)
const GlApi& gl_api() {
  static const GlApi api = load_gl_api();
  return api;
}

using Type = sim::CollisionGeometry::Type;
constexpr int kSegments = 24;  // cylinder and sphere tessellation
constexpr int kRings = 12;

struct Triangle {
  Eigen::Vector3f a, b, c, n;
};

// convex hull of a mesh's vertices as triangles (Bullet collides with the same hull)
std::vector<Triangle> hull_triangles(const sim::MeshData& mesh) {
  std::vector<Triangle> out;
  if (mesh.vertices.size() < 4) return out;
  std::vector<btScalar> coords;
  coords.reserve(3 * mesh.vertices.size());
  for (const auto& v : mesh.vertices) {
    coords.push_back(static_cast<btScalar>(v.x()));
    coords.push_back(static_cast<btScalar>(v.y()));
    coords.push_back(static_cast<btScalar>(v.z()));
  }
  btConvexHullComputer hull;
  hull.compute(coords.data(), static_cast<int>(3 * sizeof(btScalar)), static_cast<int>(mesh.vertices.size()), 0, 0);
  auto vertex = [&](int i) {
    const btVector3& p = hull.vertices[i];
    return Eigen::Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  };
  for (int f = 0; f < hull.faces.size(); ++f) {
    const btConvexHullComputer::Edge* first = &hull.edges[hull.faces[f]];
    std::vector<Eigen::Vector3f> poly;
    const btConvexHullComputer::Edge* e = first;
    do {
      poly.push_back(vertex(e->getSourceVertex()));
      e = e->getNextEdgeOfFace();
    } while (e != first && poly.size() < 1024);
    for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
      Eigen::Vector3f n = (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]);
      if (n.norm() < 1e-12f) continue;
      out.push_back({poly[0], poly[i], poly[i + 1], n.normalized()});
    }
  }
  return out;
}

void draw_unit_box(const GlApi& g) {  // [-0.5, 0.5]^3
  static const float n[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  static const float v[6][4][3] = {
      {{.5f, -.5f, -.5f}, {.5f, .5f, -.5f}, {.5f, .5f, .5f}, {.5f, -.5f, .5f}},
      {{-.5f, -.5f, -.5f}, {-.5f, -.5f, .5f}, {-.5f, .5f, .5f}, {-.5f, .5f, -.5f}},
      {{-.5f, .5f, -.5f}, {-.5f, .5f, .5f}, {.5f, .5f, .5f}, {.5f, .5f, -.5f}},
      {{-.5f, -.5f, -.5f}, {.5f, -.5f, -.5f}, {.5f, -.5f, .5f}, {-.5f, -.5f, .5f}},
      {{-.5f, -.5f, .5f}, {.5f, -.5f, .5f}, {.5f, .5f, .5f}, {-.5f, .5f, .5f}},
      {{-.5f, -.5f, -.5f}, {-.5f, .5f, -.5f}, {.5f, .5f, -.5f}, {.5f, -.5f, -.5f}}};
  g.glBegin(GL_QUADS);
  for (int f = 0; f < 6; ++f) {
    g.glNormal3fv(n[f]);
    for (int k = 0; k < 4; ++k) g.glVertex3fv(v[f][k]);
  }
  g.glEnd();
}

void draw_unit_cylinder(const GlApi& g) {  // radius 1, z in [-0.5, 0.5]
  const float step = 2.0f * std::numbers::pi_v<float> / kSegments;
  g.glBegin(GL_QUAD_STRIP);
  for (int i = 0; i <= kSegments; ++i) {
    const float c = std::cos(i * step), s = std::sin(i * step);
    g.glNormal3f(c, s, 0.0f);
    g.glVertex3f(c, s, 0.5f);
    g.glVertex3f(c, s, -0.5f);
  }
  g.glEnd();
  for (const float z : {0.5f, -0.5f}) {
    g.glBegin(GL_TRIANGLE_FAN);
    g.glNormal3f(0.0f, 0.0f, z > 0 ? 1.0f : -1.0f);
    g.glVertex3f(0.0f, 0.0f, z);
    for (int i = 0; i <= kSegments; ++i) {
      const float a = (z > 0 ? 1.0f : -1.0f) * i * step;
      g.glVertex3f(std::cos(a), std::sin(a), z);
    }
    g.glEnd();
  }
}

void draw_unit_sphere(const GlApi& g) {  // radius 1
  const float pi = std::numbers::pi_v<float>;
  for (int r = 0; r < kRings; ++r) {
    const float t0 = pi * r / kRings - pi / 2, t1 = pi * (r + 1) / kRings - pi / 2;
    g.glBegin(GL_QUAD_STRIP);
    for (int i = 0; i <= kSegments; ++i) {
      const float p = 2.0f * pi * i / kSegments;
      for (const float t : {t1, t0}) {
        const float x = std::cos(t) * std::cos(p), y = std::cos(t) * std::sin(p), z = std::sin(t);
        g.glNormal3f(x, y, z);
        g.glVertex3f(x, y, z);
      }
    }
    g.glEnd();
  }
}

}  // namespace

struct Renderer::Impl {
  OSMesaContext ctx{nullptr};
  int width{0}, height{0};
  std::vector<GLubyte> buffer;
  std::map<const sim::MeshData*, std::pair<std::shared_ptr<const sim::MeshData>, std::vector<Triangle>>> hulls;

  ~Impl() {
    if (ctx) gl_api().OSMesaDestroyContext(ctx);
  }

  const std::vector<Triangle>& hull(const std::shared_ptr<const sim::MeshData>& mesh) {
    auto it = hulls.find(mesh.get());
    if (it == hulls.end()) it = hulls.emplace(mesh.get(), std::make_pair(mesh, hull_triangles(*mesh))).first;
    return it->second.second;
  }

  void draw(const GlApi& g, const sim::SceneShape& s) {
    g.glColor4f(s.rgba[0], s.rgba[1], s.rgba[2], s.rgba[3]);
    g.glPushMatrix();
    g.glMultMatrixd(s.pose.matrix().data());
    switch (s.type) {
      case Type::kBox:
        g.glScaled(s.size.x(), s.size.y(), s.size.z());
        draw_unit_box(g);
        break;
      case Type::kSphere:
        g.glScaled(s.size.x(), s.size.x(), s.size.x());
        draw_unit_sphere(g);
        break;
      case Type::kCylinder:
        g.glScaled(s.size.x(), s.size.x(), s.size.y());
        draw_unit_cylinder(g);
        break;
      case Type::kMesh:
        if (s.mesh) {
          g.glBegin(GL_TRIANGLES);
          for (const Triangle& t : hull(s.mesh)) {
            g.glNormal3fv(t.n.data());
            g.glVertex3fv(t.a.data());
            g.glVertex3fv(t.b.data());
            g.glVertex3fv(t.c.data());
          }
          g.glEnd();
        }
        break;
    }
    g.glPopMatrix();
  }
};

Renderer::Renderer(int width, int height) : impl_(std::make_unique<Impl>()) {
  if (width < 1 || height < 1 || width > 4096 || height > 4096)
    throw std::invalid_argument("image size " + std::to_string(width) + "x" + std::to_string(height) +
                                " is outside 1..4096 pixels");
  impl_->width = width;
  impl_->height = height;
  impl_->buffer.assign(4 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  const GlApi& g = gl_api();
  impl_->ctx = g.OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!impl_->ctx) throw std::runtime_error("OSMesa could not create an off-screen GL context");
}

Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;
int Renderer::width() const { return impl_->width; }
int Renderer::height() const { return impl_->height; }

Image Renderer::render(const sim::Scene& scene, const Camera& camera) {
  Impl& m = *impl_;
  const GlApi& g = gl_api();
  if (!g.OSMesaMakeCurrent(m.ctx, m.buffer.data(), GL_UNSIGNED_BYTE, m.width, m.height))
    throw std::runtime_error("OSMesa could not bind its context");
  g.glViewport(0, 0, m.width, m.height);
  g.glClearColor(0.86f, 0.90f, 0.95f, 1.0f);
  g.glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  g.glEnable(GL_DEPTH_TEST);
  g.glEnable(GL_NORMALIZE);
  g.glShadeModel(GL_SMOOTH);
  g.glEnable(GL_LIGHTING);
  g.glEnable(GL_LIGHT0);
  g.glEnable(GL_LIGHT1);
  g.glEnable(GL_COLOR_MATERIAL);
  g.glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  g.glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_FALSE);
  const GLfloat ambient[4] = {0.35f, 0.35f, 0.35f, 1.0f};
  g.glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);

  g.glMatrixMode(GL_PROJECTION);
  const Eigen::Matrix4d p = camera.projection(static_cast<double>(m.width) / m.height);
  g.glLoadMatrixd(p.data());
  g.glMatrixMode(GL_MODELVIEW);
  const Eigen::Matrix4d v = camera.view();
  g.glLoadMatrixd(v.data());
  // lights fixed in the world: a key light from above and behind the camera side, a weak fill
  const GLfloat key_dir[4] = {0.4f, 0.6f, 1.0f, 0.0f}, key[4] = {0.65f, 0.65f, 0.62f, 1.0f};
  const GLfloat fill_dir[4] = {-0.6f, -0.3f, 0.4f, 0.0f}, fill[4] = {0.2f, 0.2f, 0.22f, 1.0f};
  const GLfloat none[4] = {0.0f, 0.0f, 0.0f, 1.0f};
  g.glLightfv(GL_LIGHT0, GL_POSITION, key_dir);
  g.glLightfv(GL_LIGHT0, GL_DIFFUSE, key);
  g.glLightfv(GL_LIGHT0, GL_AMBIENT, none);
  g.glLightfv(GL_LIGHT0, GL_SPECULAR, none);
  g.glLightfv(GL_LIGHT1, GL_POSITION, fill_dir);
  g.glLightfv(GL_LIGHT1, GL_DIFFUSE, fill);
  g.glLightfv(GL_LIGHT1, GL_AMBIENT, none);
  g.glLightfv(GL_LIGHT1, GL_SPECULAR, none);

  // opaque shapes, then translucent ones (goal markers) without depth writes
  g.glDisable(GL_BLEND);
  for (const auto& s : scene.shapes)
    if (s.rgba[3] >= 1.0f) m.draw(g, s);
  g.glEnable(GL_BLEND);
  g.glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  g.glDepthMask(GL_FALSE);
  for (const auto& s : scene.shapes)
    if (s.rgba[3] < 1.0f) m.draw(g, s);
  g.glDepthMask(GL_TRUE);
  g.glFinish();

  // the buffer's first row is the bottom of the image (OSMESA_Y_UP)
  Image out(m.width, m.height);
  auto& px = out.mutable_pixels();
  for (int y = 0; y < m.height; ++y) {
    const GLubyte* src = m.buffer.data() + 4 * static_cast<std::size_t>(m.height - 1 - y) * static_cast<std::size_t>(m.width);
    std::uint8_t* dst = px.data() + 3 * static_cast<std::size_t>(y) * static_cast<std::size_t>(m.width);
    for (int x = 0; x < m.width; ++x) {
      dst[3 * x] = src[4 * x];
      dst[3 * x + 1] = src[4 * x + 1];
      dst[3 * x + 2] = src[4 * x + 2];
    }
  }
  return out;
}

}  // namespace actionshift::render
