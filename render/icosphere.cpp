#include "render/icosphere.h"

#include <algorithm>
#include <map>
#include <utility>

namespace vdmap::render {

Icosphere makeIcosphere(int subdivisions) {
  const float t = 1.6180339887f;
  Icosphere s;
  s.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& v : s.vertices) v = glm::normalize(v);
  s.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<unsigned, unsigned>, unsigned> midpoints;
    auto midpoint = [&](unsigned a, unsigned b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      s.vertices.push_back(glm::normalize(s.vertices[a] + s.vertices[b]));
      const unsigned id = static_cast<unsigned>(s.vertices.size() - 1);
      midpoints.emplace(key, id);
      return id;
    };
    std::vector<glm::uvec3> next;
    for (const auto& tri : s.triangles) {
      const unsigned ab = midpoint(tri.x, tri.y), bc = midpoint(tri.y, tri.z), ca = midpoint(tri.z, tri.x);
      next.insert(next.end(), {{tri.x, ab, ca}, {tri.y, bc, ab}, {tri.z, ca, bc}, {ab, bc, ca}});
    }
    s.triangles = std::move(next);
  }
  return s;
}

}  // namespace vdmap::render
