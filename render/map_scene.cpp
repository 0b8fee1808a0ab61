#include "render/map_scene.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

#include "mapping/global_map/level_up.h"
#include "mapping/io/camera_config.h"
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

glm::vec3 estimateUp(std::span<const Transform> T_W_C, std::span<const Ellipsoid> map, UpFrom* from) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const Transform& T : T_W_C) up -= T.linear().col(1);
  if (from) *from = UpFrom::kCameras;
  // Cameras turned every way (or none) give no direction: the map's level planes do, else the
  // +z convention.
  if (T_W_C.empty() || up.norm() < 0.3 * static_cast<double>(T_W_C.size())) {
    const std::optional<LevelUp> level = levelUp(map);
    if (from) *from = level ? UpFrom::kLevelPlanes : UpFrom::kDefault;
    if (!level) return {0.f, 0.f, 1.f};
    return {static_cast<float>(level->up.x()), static_cast<float>(level->up.y()), static_cast<float>(level->up.z())};
  }
  up.normalize();
  // The largest plane of the map whose normal lies within 40 degrees of the cameras' up: the
  // floor, a table, a ceiling; each is level, so its normal is the true up. RANSAC over at most
  // ~3000 means (evenly strided), 2 cm inliers, a fixed seed (the same map gives the same up);
  // cheap enough for the UI thread, once per framing.
  const std::size_t stride = std::max<std::size_t>(1, map.size() / 3000);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < map.size(); i += stride) points.push_back(map[i].mean);
  if (points.size() < 30) return {static_cast<float>(up.x()), static_cast<float>(up.y()), static_cast<float>(up.z())};
  const double cos_limit = std::cos(40.0 * M_PI / 180.0), inlier_m = 0.02;
  std::mt19937 rng(1);
  std::size_t best = 0;
  Eigen::Vector3d best_normal = up;
  double best_offset = 0.0;
  std::vector<std::size_t> near;
  for (int it = 0; it < 300; ++it) {
    // Three points of one neighbourhood (0.3 m): far likelier to lie on one surface than three
    // drawn from the whole map, where a floor of 10% of it would be hit once in 1000 draws.
    const Eigen::Vector3d& a = points[rng() % points.size()];
    near.clear();
    for (std::size_t i = 0; i < points.size(); ++i)
      if ((points[i] - a).squaredNorm() < 0.09) near.push_back(i);
    if (near.size() < 3) continue;
    const Eigen::Vector3d& b = points[near[rng() % near.size()]];
    const Eigen::Vector3d& c = points[near[rng() % near.size()]];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-9) continue;
    n.normalize();
    if (n.dot(up) < 0) n = -n;
    if (n.dot(up) < cos_limit) continue;
    const double offset = n.dot(a);
    std::size_t inliers = 0;
    for (const Eigen::Vector3d& p : points) inliers += std::abs(n.dot(p) - offset) < inlier_m;
    if (inliers > best) best = inliers, best_normal = n, best_offset = offset;
  }
  // A plane of at least 5% of the map: refine it by least squares over its inliers (twice, the
  // inliers re-counted with the refined plane).
  if (best * 20 >= points.size()) {
    for (int round = 0; round < 3; ++round) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      std::vector<Eigen::Vector3d> inliers;
      for (const Eigen::Vector3d& p : points)
        if (std::abs(best_normal.dot(p) - best_offset) < inlier_m) inliers.push_back(p), mean += p;
      if (inliers.size() < 3) break;
      mean /= static_cast<double>(inliers.size());
      Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
      for (const Eigen::Vector3d& p : inliers) scatter += (p - mean) * (p - mean).transpose();
      const Eigen::Vector3d n = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
      best_normal = n.dot(up) < 0 ? Eigen::Vector3d(-n) : n;
      best_offset = best_normal.dot(mean);
    }
    up = best_normal;
  }
  return {static_cast<float>(up.x()), static_cast<float>(up.y()), static_cast<float>(up.z())};
}

GraphScene graphSceneOf(const KeyframeGraph& graph, const MapperState& state, const PinholeCamera& camera,
                        bool tracked) {
  GraphScene scene;
  scene.camera = camera;
  for (const Keyframe& k : graph.keyframes()) scene.keyframes.push_back(k.T_W_K);
  for (const CovisibilityEdge& e : graph.edges().edges())
    scene.edges.push_back({e.a, e.b, static_cast<float>(e.weight)});
  for (const LoopClosure& l : state.loops) scene.loops.push_back({l.from, l.to, 1.f});
  // Sessions since format 4 store every mapped frame's pose; older ones only the keyframes'.
  const int n = static_cast<int>(scene.keyframes.size());
  for (const FramePose& f : state.frame_poses)
    if (f.keyframe >= 0 && f.keyframe < n) scene.trajectory.push_back(scene.keyframes[f.keyframe] * f.T_K_C);
  if (state.frame_poses.empty()) scene.trajectory = scene.keyframes;
  scene.current_keyframe = state.current_keyframe;
  scene.tracked = tracked;
  return scene;
}

GraphScene graphSceneOf(const StaticMap& map) {
  GraphScene scene;
  scene.camera = cameraPreset(kStaticMapCamera);
  for (const StampedPose& k : map.keyframes) scene.keyframes.push_back(k.T_W_C);
  for (const CovisibilityEdge& e : map.edges) scene.edges.push_back({e.a, e.b, static_cast<float>(e.weight)});
  if (map.keyframes.empty()) return scene;
  // Each frame relative to the newest keyframe at or before it, as the workbench holds it.
  std::size_t k = 0;
  for (const StampedPose& p : map.trajectory) {
    while (k + 1 < map.keyframes.size() && map.keyframes[k + 1].t <= p.t) ++k;
    scene.trajectory.push_back(scene.keyframes[k] * (scene.keyframes[k].inverse() * p.T_W_C));
  }
  if (map.trajectory.empty()) scene.trajectory = scene.keyframes;
  return scene;
}

}  // namespace vdmap::render
