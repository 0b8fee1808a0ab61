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

/// How ellipsoids (and their centres and 2-D projections) are coloured.
enum class ColorMode { kRgb, kKeyframe, kUncertainty, kCount };

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
