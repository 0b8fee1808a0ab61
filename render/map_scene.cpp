#include "render/map_scene.h"

#include <algorithm>

#include "render/colormap.h"

namespace vdmap::render {
namespace {

EllipsoidInstance toInstance(const Ellipsoid& e) {
  EllipsoidInstance out;
  out.mean = {e.mean.x(), e.mean.y(), e.mean.z()};
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) out.cov[c][r] = static_cast<float>(e.cov(r, c));
  for (int k = 0; k < 3; ++k) out.rgb[k] = static_cast<std::uint8_t>(std::clamp(e.color[k] + 0.5f, 0.f, 255.f));
  out.keyframe = e.keyframe;
  out.count = e.count;
  return out;
}

}  // namespace

std::vector<EllipsoidInstance> toInstances(std::span<const Ellipsoid> ellipsoids) {
  std::vector<EllipsoidInstance> out;
  out.reserve(ellipsoids.size());
  for (const Ellipsoid& e : ellipsoids) out.push_back(toInstance(e));
  return out;
}

std::vector<EllipsoidInstance> toInstances(std::span<const EllipsoidRecord> records) {
  std::vector<EllipsoidInstance> out(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    const EllipsoidRecord& r = records[i];
    out[i].mean = {r.mean.x(), r.mean.y(), r.mean.z()};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) out[i].cov[c][k] = r.cov(k, c);
    out[i].rgb = {r.rgb[0], r.rgb[1], r.rgb[2]};
    out[i].keyframe = r.keyframe;
    out[i].count = r.count;
  }
  return out;
}

ColoredMesh toColoredMesh(const ColoredTriangleMesh& mesh) {
  ColoredMesh out;
  out.positions.reserve(mesh.positions.size());
  for (const auto& p : mesh.positions) out.positions.emplace_back(p.x(), p.y(), p.z());
  for (const auto& c : mesh.colors) out.colors.emplace_back(c[0], c[1], c[2]);
  for (const auto& t : mesh.triangles) out.triangles.emplace_back(t[0], t[1], t[2]);
  return out;
}

ColoredLines keyframeGraphLines(const KeyframeGraph& graph, const PinholeCamera& camera, float frustum_depth_m) {
  ColoredLines lines;
  std::vector<Transform> poses;
  for (const Keyframe& k : graph.keyframes()) {
    addFrustum(lines, camera, k.T_W_K, frustum_depth_m, keyframeColor(k.id));
    poses.push_back(k.T_W_K);
  }
  std::vector<GraphEdge> edges;
  for (const CovisibilityEdge& e : graph.edges().edges())
    edges.push_back({e.a, e.b, static_cast<float>(e.weight)});
  addEdges(lines, poses, edges);
  addTrajectory(lines, poses, {150, 150, 150});
  return lines;
}

}  // namespace vdmap::render
