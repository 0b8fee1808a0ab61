#include "render/map_scene.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

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

glm::vec3 estimateUp(std::span<const Transform> T_W_C, std::span<const Ellipsoid> map) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const Transform& T : T_W_C) up -= T.linear().col(1);
  // Cameras turned every way (or none) give no direction: keep the +z convention.
  if (up.norm() < 0.3 * static_cast<double>(T_W_C.size()) || T_W_C.empty()) return {0.f, 0.f, 1.f};
  up.normalize();
  // At most ~4000 ellipsoids (evenly strided): enough for the mean normal, cheap on the UI thread.
  const std::size_t stride = std::max<std::size_t>(1, map.size() / 4000);
  const double cos_limit = std::cos(25.0 * M_PI / 180.0);
  Eigen::Vector3d normals = Eigen::Vector3d::Zero();
  double weight = 0.0;
  for (std::size_t i = 0; i < map.size(); i += stride) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.compute(map[i].cov);
    const Eigen::Vector3d lambda = eig.eigenvalues();  // ascending
    if (!(lambda[0] < 0.1 * lambda[1])) continue;      // not flat: no normal
    Eigen::Vector3d n = eig.eigenvectors().col(0);
    if (n.dot(up) < 0) n = -n;
    if (n.dot(up) < cos_limit) continue;
    normals += map[i].count * n;
    weight += map[i].count;
  }
  if (weight > 0 && normals.norm() > 0) up = normals.normalized();
  return {static_cast<float>(up.x()), static_cast<float>(up.y()), static_cast<float>(up.z())};
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
