#pragma once
// Plain render-side inputs. render/ does not depend on the mapping containers: the app (or a
// test) fills these from whatever it holds. Positions are in the world frame, metres.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/type_precision.hpp>

namespace vdmap::render {

/// One NDT ellipsoid: mean (W), covariance (W, m^2), mean colour, owning keyframe, point count.
struct EllipsoidInstance {
  glm::vec3 mean{0.f};
  glm::mat3 cov{1e-4f};
  glm::u8vec3 rgb{200, 200, 200};
  int keyframe = 0;
  std::uint32_t count = 1;
};

/// How ellipsoids (and their centres and 2-D projections) are coloured. kHeight: by height above
/// the floor (HeightFrame), over the slice when one is on.
enum class ColorMode { kRgb, kKeyframe, kUncertainty, kCount, kHeight };

/// What of the map is drawn: its ellipsoids, their centres as points, or nothing (the map hidden;
/// trajectories, frustums and the graph are still drawn).
enum class DrawMode { kEllipsoids, kCentres, kNone };
/// Names in view files, `render --draw` and the window's combo, indexed by DrawMode.
inline constexpr const char* kDrawModeNames[] = {"ellipsoids", "centres", "none"};

/// How the surface mesh layer is drawn: grey lit by its faces' normals, its vertex colours lit the
/// same way, or its triangles' edges.
enum class MeshStyle { kShaded, kColour, kWireframe };
/// Names in the settings file, view files and `render --mesh-style`, indexed by MeshStyle.
inline constexpr const char* kMeshStyleNames[] = {"shaded", "colour", "wireframe"};

/// Where heights are measured from: height = dot(p, up) - floor_m. The floor is the 2nd
/// percentile of dot(mean, up) over the map (heightFrame, view_framing.h).
struct HeightFrame {
  glm::vec3 up{0.f, 0.f, 1.f};
  float floor_m = 0.f;
  float height(const glm::vec3& p) const { return glm::dot(p, up) - floor_m; }
  bool operator==(const HeightFrame&) const = default;
};

/// A slice of the map along the up axis: only ellipsoids whose centre's height above the floor
/// lies in [lo_m, hi_m] are drawn, picked and framed (whole ellipsoids are kept or dropped).
struct HeightSlice {
  bool on = false;
  float lo_m = 0.f, hi_m = 1.f;
  /// Whether a centre at height `h` is kept (always when the slice is off).
  bool keeps(float h) const { return !on || (h >= lo_m && h <= hi_m); }
  bool operator==(const HeightSlice&) const = default;
};

/// A triangle mesh with per-vertex colours; triangles index into positions.
struct ColoredMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::u8vec3> colors;
  std::vector<glm::uvec3> triangles;
};

/// A line segment list with per-vertex colours (vertices 2i, 2i+1 form segment i).
struct ColoredLines {
  std::vector<glm::vec3> positions;
  std::vector<glm::u8vec3> colors;
  void add(const glm::vec3& a, const glm::vec3& b, const glm::u8vec3& color) {
    positions.push_back(a);
    positions.push_back(b);
    colors.push_back(color);
    colors.push_back(color);
  }
};

}  // namespace vdmap::render
