#include "mapping/synth/builtin_scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

#include "mapping/io/camera_config.h"

namespace vdmap {
namespace {

using Color = std::array<std::uint8_t, 3>;

// A deterministic hash of integer coordinates -> [0, 1).
double hash01(int a, int b, int c) {
  std::uint64_t h = 0x9e3779b97f4a7c15ull;
  for (const int v : {a, b, c}) {
    h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(v)) + 0x632be59bd9b4e019ull + (h << 6) + (h >> 2);
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
  }
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53);
}

class MeshBuilder {
 public:
  MeshBuilder(ColoredTriangleMesh& mesh, double tile_m) : mesh_(mesh), tile_m_(tile_m) {}

  // A rectangle origin + s * eu + t * ev (s, t in [0, 1]) cut into flat-coloured tiles. The
  // tile colour multiplies `base` by blocky noise at two scales (tile and 4 tiles) plus a
  // sparse set of bright/dark marks, so every region has corners at several scales.
  void tiledQuad(const Eigen::Vector3f& origin, const Eigen::Vector3f& eu, const Eigen::Vector3f& ev,
                 const Color& base) {
    const int nu = std::max(1, static_cast<int>(std::lround(eu.norm() / tile_m_)));
    const int nv = std::max(1, static_cast<int>(std::lround(ev.norm() / tile_m_)));
    const int surface = surfaces_++;
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const Eigen::Vector3f a = origin + eu * (float(i) / nu) + ev * (float(j) / nv);
        const Eigen::Vector3f b = a + eu / float(nu), d = a + ev / float(nv), c = b + ev / float(nv);
        quad(a, b, c, d, tileColor(base, surface, i, j));
      }
  }

  // An axis-aligned box [lo, hi], every face tiled.
  void box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, const Color& base) {
    const Eigen::Vector3f s = hi - lo;
    const Eigen::Vector3f x(s.x(), 0, 0), y(0, s.y(), 0), z(0, 0, s.z());
    tiledQuad(lo, x, y, base);
    tiledQuad(lo + z, x, y, base);
    tiledQuad(lo, x, z, base);
    tiledQuad(lo + y, x, z, base);
    tiledQuad(lo, y, z, base);
    tiledQuad(lo + x, y, z, base);
  }

  // A sphere of latitude/longitude patches, each a flat colour (a beach-ball pattern).
  void sphere(const Eigen::Vector3f& c, float r, const Color& base) {
    const int nlat = 16, nlon = 32, surface = surfaces_++;
    auto point = [&](int i, int j) {
      const double th = M_PI * i / nlat, ph = 2 * M_PI * j / nlon;
      return Eigen::Vector3f(
          c + r * Eigen::Vector3f(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    };
    for (int i = 0; i < nlat; ++i)
      for (int j = 0; j < nlon; ++j)
        quad(point(i, j), point(i, j + 1), point(i + 1, j + 1), point(i + 1, j),
             tileColor(((i / 2 + j / 4) % 2) ? base : Color{240, 240, 230}, surface, i, j));
  }

  // A vertical cylinder (side and top) with stripes.
  void cylinder(const Eigen::Vector3f& bottom, float r, float h, const Color& base) {
    const int n = 40, rings = std::max(1, static_cast<int>(h / tile_m_)), surface = surfaces_++;
    auto point = [&](int j, int k) {
      const double ph = 2 * M_PI * j / n;
      return Eigen::Vector3f(bottom + Eigen::Vector3f(r * std::cos(ph), r * std::sin(ph), h * k / rings));
    };
    for (int k = 0; k < rings; ++k)
      for (int j = 0; j < n; ++j)
        quad(point(j, k), point(j + 1, k), point(j + 1, k + 1), point(j, k + 1),
             tileColor((j / 3 + k / 2) % 2 ? base : Color{30, 30, 40}, surface, j, k));
    const Eigen::Vector3f top = bottom + Eigen::Vector3f(0, 0, h);
    for (int j = 0; j < n; ++j) triangle(top, point(j, rings), point(j + 1, rings), tileColor(base, surface, j, -1));
  }

 private:
  Color tileColor(const Color& base, int surface, int i, int j) const {
    const double fine = hash01(surface, i, j), coarse = hash01(surface + 1000, i / 4, j / 4);
    double f = 0.45 + 0.35 * fine + 0.35 * coarse;
    const double mark = hash01(surface + 2000, i, j);
    if (mark > 0.97) f = 1.6;       // bright specks
    else if (mark < 0.03) f = 0.1;  // dark specks
    Color c;
    for (int k = 0; k < 3; ++k) c[k] = static_cast<std::uint8_t>(std::clamp(base[k] * f, 0.0, 255.0));
    return c;
  }
  void quad(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c, const Eigen::Vector3f& d,
            const Color& color) {
    const auto base = static_cast<std::uint32_t>(mesh_.positions.size());
    mesh_.positions.insert(mesh_.positions.end(), {a, b, c, d});
    mesh_.colors.insert(mesh_.colors.end(), 4, color);
    mesh_.triangles.push_back({base, base + 1, base + 2});
    mesh_.triangles.push_back({base, base + 2, base + 3});
  }
  void triangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c, const Color& color) {
    const auto base = static_cast<std::uint32_t>(mesh_.positions.size());
    mesh_.positions.insert(mesh_.positions.end(), {a, b, c});
    mesh_.colors.insert(mesh_.colors.end(), 3, color);
    mesh_.triangles.push_back({base, base + 1, base + 2});
  }

  ColoredTriangleMesh& mesh_;
  double tile_m_;
  int surfaces_ = 0;
};

Transform lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();  // image right
  const Eigen::Vector3d y = z.cross(x);                                      // image down
  Transform T = Transform::Identity();
  T.linear() << x, y, z;
  T.translation() = eye;
  return T;
}

}  // namespace

BuiltinScene makeBuiltinScene(const BuiltinSceneParams& params) {
  BuiltinScene scene;
  scene.camera = cameraPreset("tum-default");
  MeshBuilder b(scene.mesh, params.texture_tile_m);
  const float X = 2.5f, Y = 2.f, H = 2.6f;
  using V = Eigen::Vector3f;
  b.tiledQuad(V(-X, -Y, 0), V(2 * X, 0, 0), V(0, 2 * Y, 0), {170, 140, 100});  // floor (wood)
  b.tiledQuad(V(-X, -Y, H), V(2 * X, 0, 0), V(0, 2 * Y, 0), {220, 220, 215});  // ceiling
  b.tiledQuad(V(-X, -Y, 0), V(2 * X, 0, 0), V(0, 0, H), {200, 120, 110});      // wall y = -Y
  b.tiledQuad(V(-X, Y, 0), V(2 * X, 0, 0), V(0, 0, H), {110, 160, 200});       // wall y = +Y
  b.tiledQuad(V(-X, -Y, 0), V(0, 2 * Y, 0), V(0, 0, H), {140, 190, 120});      // wall x = -X
  b.tiledQuad(V(X, -Y, 0), V(0, 2 * Y, 0), V(0, 0, H), {210, 200, 120});       // wall x = +X
  // Table in the middle of the walk: top and four legs.
  b.box(V(-0.5f, -0.3f, 0.72f), V(0.5f, 0.3f, 0.77f), {150, 90, 50});
  for (const float sx : {-0.45f, 0.4f})
    for (const float sy : {-0.25f, 0.2f}) b.box(V(sx, sy, 0), V(sx + 0.05f, sy + 0.05f, 0.72f), {80, 60, 40});
  // Boxes near the walls and one on the table.
  b.box(V(1.7f, -1.8f, 0), V(2.3f, -1.2f, 0.5f), {190, 150, 90});
  b.box(V(1.8f, -1.7f, 0.5f), V(2.2f, -1.3f, 0.8f), {90, 140, 190});
  b.box(V(-2.3f, 1.3f, 0), V(-1.7f, 1.8f, 0.45f), {160, 80, 160});
  b.box(V(-0.2f, -0.15f, 0.77f), V(0.1f, 0.1f, 0.95f), {230, 90, 60});
  // A shelf against the wall x = +X: two sides and four boards.
  b.box(V(2.1f, 0.2f, 0), V(2.45f, 0.24f, 1.8f), {120, 100, 80});
  b.box(V(2.1f, 1.36f, 0), V(2.45f, 1.4f, 1.8f), {120, 100, 80});
  for (int k = 0; k < 4; ++k)
    b.box(V(2.1f, 0.24f, 0.1f + 0.55f * k), V(2.45f, 1.36f, 0.13f + 0.55f * k), {140, 110, 85});
  b.box(V(2.15f, 0.35f, 0.13f), V(2.4f, 0.6f, 0.45f), {60, 150, 90});
  b.box(V(2.15f, 0.8f, 0.68f), V(2.4f, 1.2f, 0.9f), {200, 60, 80});
  // Round objects.
  b.sphere(V(0.25f, 0.1f, 0.89f), 0.12f, {220, 40, 40});
  b.sphere(V(-1.9f, -1.5f, 0.25f), 0.25f, {40, 80, 220});
  b.cylinder(V(-2.0f, 0.0f, 0), 0.18f, 0.9f, {230, 180, 40});
  b.cylinder(V(2.27f, 0.95f, 1.23f), 0.08f, 0.25f, {50, 170, 200});

  // The walk: an ellipse around the table at eye height, looking ahead and outwards at a point
  // on a larger ellipse, so the camera sweeps every wall and comes back to where it began.
  // Further laps vary the ellipse's size, the eye height, the gaze (ahead, sideways, back,
  // down at the floor, up) and the direction of travel.
  if (params.frames < 2 || params.laps < 1)
    throw std::invalid_argument("the built-in walk needs at least 2 frames per lap and 1 lap");
  struct Lap {
    double radius, eye_dz, gaze_rad, target_z, direction;
  };
  static const Lap kLaps[8] = {{1.0, 0.0, 0.9, 0.75, 1},  {0.65, 0.3, 2.4, 0.4, -1}, {1.35, -0.3, -0.9, 1.3, 1},
                               {0.8, 0.5, 3.4, 0.1, -1},  {1.3, 0.25, 1.6, 2.3, 1},  {0.7, -0.15, -2.2, 0.9, -1},
                               {1.15, 0.55, 0.2, 0.2, 1}, {0.9, -0.2, 4.4, 1.6, -1}};
  const int n = params.frames;
  for (int lap = 0; lap < params.laps; ++lap) {
    const Lap& l = kLaps[lap % 8];
    for (int i = 0; i < n; ++i) {
      const double a = l.direction * 2.0 * M_PI * i / n;
      const Eigen::Vector3d eye(l.radius * 1.2 * std::cos(a), l.radius * 0.95 * std::sin(a),
                                1.35 + l.eye_dz + 0.08 * std::sin(3 * a));
      const double b2 = a + l.direction * l.gaze_rad;
      const Eigen::Vector3d target(2.4 * std::cos(b2), 1.9 * std::sin(b2), l.target_z + 0.15 * std::sin(2 * a));
      const int k = lap * n + i;
      scene.trajectory.push_back({k / params.fps, lookAt(eye, target)});
    }
  }
  return scene;
}

}  // namespace vdmap
