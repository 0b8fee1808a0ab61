#include "render/view_framing.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "render/map_scene.h"

namespace vdmap::render {

std::pair<glm::vec3, glm::vec3> frameBounds(std::span<const glm::vec3> means, const GraphScene& graph) {
  ColoredLines cameras;
  for (const Transform& T : graph.keyframes) addFrustum(cameras, graph.camera, T, kKeyframeFrustumDepthM, {});
  for (const auto* poses : {&graph.trajectory, &graph.groundtruth})
    for (const Transform& T : *poses)
      cameras.positions.emplace_back(T.translation().x(), T.translation().y(), T.translation().z());
  if (means.empty() && cameras.positions.empty()) return robustBounds({});
  auto [lo, hi] = means.empty() ? std::pair{cameras.positions[0], cameras.positions[0]}
                                : robustBounds(std::vector<glm::vec3>(means.begin(), means.end()));
  for (const glm::vec3& p : cameras.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  return {lo, hi};
}

DrawnBounds drawnBounds(std::span<const Ellipsoid> map, float sigma, DrawMode mode, const HeightSlice& slice,
                        const HeightFrame& frame) {
  DrawnBounds out;
  if (mode == DrawMode::kNone) return out;
  std::vector<glm::vec3> means;
  means.reserve(map.size());
  for (const Ellipsoid& e : map) {
    const glm::vec3 m(e.mean.x(), e.mean.y(), e.mean.z());
    if (slice.keeps(frame.height(m))) means.push_back(m);
  }
  if (means.empty()) return out;
  const auto [rlo, rhi] = robustBounds(means);
  const glm::vec3 centre = 0.5f * (rlo + rhi);
  const float reach = glm::length(rhi - rlo);
  for (const Ellipsoid& e : map) {
    const glm::vec3 m(e.mean.x(), e.mean.y(), e.mean.z());
    if (!slice.keeps(frame.height(m))) continue;
    if (glm::length(m - centre) > reach) {
      ++out.strays;
      continue;
    }
    glm::vec3 half(0.f);
    if (mode == DrawMode::kEllipsoids)
      for (int k = 0; k < 3; ++k) half[k] = sigma * static_cast<float>(std::sqrt(std::max(0.0, e.cov(k, k))));
    if (out.empty) out.lo = m - half, out.hi = m + half, out.empty = false;
    else out.lo = glm::min(out.lo, m - half), out.hi = glm::max(out.hi, m + half);
    ++out.drawn;
  }
  return out;
}

std::pair<glm::vec3, glm::vec3> frameBounds(const DrawnBounds& map, const GraphScene& graph) {
  ColoredLines cameras;
  for (const Transform& T : graph.keyframes) addFrustum(cameras, graph.camera, T, kKeyframeFrustumDepthM, {});
  for (const auto* poses : {&graph.trajectory, &graph.groundtruth})
    for (const Transform& T : *poses)
      cameras.positions.emplace_back(T.translation().x(), T.translation().y(), T.translation().z());
  if (map.empty && cameras.positions.empty()) return robustBounds({});
  auto [lo, hi] = map.empty ? std::pair{cameras.positions[0], cameras.positions[0]} : std::pair{map.lo, map.hi};
  for (const glm::vec3& p : cameras.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  return {lo, hi};
}

HeightFrame heightFrame(std::span<const Ellipsoid> map, const glm::vec3& up_in) {
  HeightFrame frame;
  frame.up = glm::length(up_in) > 1e-6f ? glm::normalize(up_in) : glm::vec3(0.f, 0.f, 1.f);
  if (map.empty()) return frame;
  std::vector<float> h;
  h.reserve(map.size());
  for (const Ellipsoid& e : map) h.push_back(glm::dot(glm::vec3(e.mean.x(), e.mean.y(), e.mean.z()), frame.up));
  const std::size_t a = h.size() * 2 / 100;
  std::nth_element(h.begin(), h.begin() + static_cast<long>(a), h.end());
  frame.floor_m = h[a];
  return frame;
}

glm::vec3 upDirection(UpAxis axis, std::span<const Transform> cameras, std::span<const Ellipsoid> map) {
  switch (axis) {
    case UpAxis::kPlusZ: return {0.f, 0.f, 1.f};
    case UpAxis::kPlusY: return {0.f, 1.f, 0.f};
    case UpAxis::kMinusY: return {0.f, -1.f, 0.f};
    case UpAxis::kData: break;
  }
  return estimateUp(cameras, map);
}

OrbitCamera defaultOrbit(const std::pair<glm::vec3, glm::vec3>& bounds, const glm::vec3& up, float aspect,
                         float fov_y_deg) {
  OrbitCamera cam = OrbitCamera::framing(bounds.first, bounds.second, up, aspect);
  if (fov_y_deg != cam.fov_y_deg) {
    cam.fov_y_deg = fov_y_deg;
    cam.frame(bounds.first, bounds.second, aspect);
  }
  return cam;
}

OrbitCamera orbitCamera(const ViewSpec& spec, const ViewScene& scene, int width, int height) {
  if (spec.look_at) return OrbitCamera::fromLookAt(spec.look_at->eye, spec.look_at->target, spec.look_at->up,
                                                   spec.look_at->fov_y_deg);
  const float aspect = static_cast<float>(width) / static_cast<float>(std::max(1, height));
  OrbitCamera cam = defaultOrbit(scene.bounds, scene.up, aspect, spec.fov_y_deg);
  if (spec.orbit) {
    cam.yaw = glm::radians(spec.orbit->azimuth_deg);
    const float limit = glm::radians(89.f);
    cam.pitch = std::clamp(glm::radians(spec.orbit->elevation_deg), -limit, limit);
    if (spec.orbit->distance_m) cam.distance_m = *spec.orbit->distance_m;
    else cam.fit(scene.bounds.first, scene.bounds.second, aspect);  // framed from these angles
  }
  return cam;
}

FramedView viewCamera(const ViewSpec& spec, const ViewScene& scene, int width, int height) {
  if (spec.kind == ViewKind::kKeyframe) {
    const PixelRect r = letterbox(width, height, scene.camera.width, scene.camera.height);
    return {ViewCamera::fromPinhole(scene.camera, scene.T_W_K, r.width, r.height), r};
  }
  // An explicit camera is drawn as given (the window's OrbitCamera::view is this lookAt of its
  // eye, so a saved view reproduces the window's camera exactly).
  if (spec.look_at)
    return {ViewCamera::lookAt(spec.look_at->eye, spec.look_at->target, spec.look_at->up, spec.look_at->fov_y_deg,
                               width, height),
            {0, 0, width, height}};
  return {orbitCamera(spec, scene, width, height).view(width, height), {0, 0, width, height}};
}

}  // namespace vdmap::render
