#include "render/scene_lines.h"

#include "render/colormap.h"

namespace vdmap::render {
namespace {
glm::vec3 toGlm(const Eigen::Vector3d& p) { return {float(p.x()), float(p.y()), float(p.z())}; }
}  // namespace

void addFrustum(ColoredLines& lines, const PinholeCamera& camera, const Transform& T_W_K, float depth_m,
                const glm::u8vec3& color) {
  const glm::vec3 c = toGlm(T_W_K.translation());
  const double u[4] = {-0.5, camera.width - 0.5, camera.width - 0.5, -0.5};
  const double v[4] = {-0.5, -0.5, camera.height - 0.5, camera.height - 0.5};
  glm::vec3 corner[4];
  for (int i = 0; i < 4; ++i) corner[i] = toGlm(T_W_K * camera.backProject(u[i], v[i], depth_m));
  for (int i = 0; i < 4; ++i) {
    lines.add(c, corner[i], color);
    lines.add(corner[i], corner[(i + 1) % 4], color);
  }
  // A tick on the top edge says which way is up in the image.
  const glm::vec3 top = 0.5f * (corner[0] + corner[1]);
  lines.add(top, top + 0.25f * (top - 0.5f * (corner[2] + corner[3])), color);
}

void addEdges(ColoredLines& lines, std::span<const Transform> T_W_K, std::span<const GraphEdge> edges,
              const std::optional<glm::u8vec3>& color) {
  for (const GraphEdge& e : edges) {
    if (e.a < 0 || e.b < 0 || e.a >= int(T_W_K.size()) || e.b >= int(T_W_K.size())) continue;
    lines.add(toGlm(T_W_K[e.a].translation()), toGlm(T_W_K[e.b].translation()), color ? *color : colormap(e.weight));
  }
}

void addTrajectory(ColoredLines& lines, std::span<const Transform> T_W_C, const glm::u8vec3& color) {
  for (std::size_t i = 1; i < T_W_C.size(); ++i)
    lines.add(toGlm(T_W_C[i - 1].translation()), toGlm(T_W_C[i].translation()), color);
}

}  // namespace vdmap::render
