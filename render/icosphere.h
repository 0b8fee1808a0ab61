#pragma once
#include <vector>

#include <glm/glm.hpp>

namespace vdmap::render {

/// A unit sphere triangulated from an icosahedron; `subdivisions` 0 gives 12 vertices / 20
/// triangles, 1 gives 42 / 80, 2 gives 162 / 320. Vertex positions are also the normals.
struct Icosphere {
  std::vector<glm::vec3> vertices;
  std::vector<glm::uvec3> triangles;
};
Icosphere makeIcosphere(int subdivisions);

}  // namespace vdmap::render
