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
                        const HeightFrame& frame, const glm::mat3& axes) {
  DrawnBounds out;
  out.axes = axes;
  if (mode == DrawMode::kNone) return out;
  const glm::mat3 to_box = glm::transpose(axes);
  std::vector<glm::vec3> means;
  means.reserve(map.size());
  for (const Ellipsoid& e : map) {
    const glm::vec3 m(e.mean.x(), e.mean.y(), e.mean.z());
    if (slice.keeps(frame.height(m))) means.push_back(to_box * m);
  }
  if (means.empty()) return out;
  const auto [rlo, rhi] = robustBounds(means);
  const glm::vec3 centre = 0.5f * (rlo + rhi);
  const float reach = glm::length(rhi - rlo);
  for (const Ellipsoid& e : map) {
    const glm::vec3 world(e.mean.x(), e.mean.y(), e.mean.z());
    if (!slice.keeps(frame.height(world))) continue;
    const glm::vec3 m = to_box * world;
    if (glm::length(m - centre) > reach) {
      ++out.strays;
      continue;
    }
    // The ellipsoid's extent along axis n at sigma: sigma sqrt(n' cov n).
    glm::vec3 half(0.f);
    if (mode == DrawMode::kEllipsoids)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d n(axes[k].x, axes[k].y, axes[k].z);
        half[k] = sigma * static_cast<float>(std::sqrt(std::max(0.0, n.dot(e.cov * n))));
      }
    if (out.empty) out.lo = m - half, out.hi = m + half, out.empty = false;
    else out.lo = glm::min(out.lo, m - half), out.hi = glm::max(out.hi, m + half);
    ++out.drawn;
  }
  return out;
}

FrameBox frameBounds(const DrawnBounds& map, const GraphScene& graph) {
  ColoredLines cameras;
  for (const Transform& T : graph.keyframes) addFrustum(cameras, graph.camera, T, kKeyframeFrustumDepthM, {});
  for (const auto* poses : {&graph.trajectory, &graph.groundtruth})
    for (const Transform& T : *poses)
      cameras.positions.emplace_back(T.translation().x(), T.translation().y(), T.translation().z());
  if (map.empty && cameras.positions.empty()) return FrameBox(robustBounds({}));
  const glm::mat3 to_box = glm::transpose(map.axes);
  glm::vec3 lo = map.lo, hi = map.hi;
  if (map.empty) lo = hi = to_box * cameras.positions[0];
  for (const glm::vec3& p : cameras.positions) lo = glm::min(lo, to_box * p), hi = glm::max(hi, to_box * p);
  return {lo, hi, map.axes};
}

void holdPoints(DrawnBounds& drawn, std::span<const glm::vec3> points) {
  const glm::mat3 to_box = glm::transpose(drawn.axes);
  for (const glm::vec3& p : points) {
    const glm::vec3 q = to_box * p;
    drawn.lo = drawn.empty ? q : glm::min(drawn.lo, q);
    drawn.hi = drawn.empty ? q : glm::max(drawn.hi, q);
    drawn.empty = false;
  }
}

glm::mat3 frameAxes(std::span<const Ellipsoid> map, const glm::vec3& up_in) {
  const glm::vec3 up = glm::length(up_in) > 1e-6f ? glm::normalize(up_in) : glm::vec3(0.f, 0.f, 1.f);
  // A horizon basis (a, b), then the principal direction of the means' horizontal spread.
  const glm::vec3 a = glm::normalize(glm::cross(up, std::abs(up.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
  const glm::vec3 b = glm::cross(up, a);
  // The turn about up (0..90 degrees, 5-degree steps) whose box of the means' horizontal
  // 2-98 % extents is smallest in area: a room's walls. At most ~20k means are looked at.
  const std::size_t stride = std::max<std::size_t>(1, map.size() / 20000);
  std::vector<glm::vec2> flat;
  for (std::size_t i = 0; i < map.size(); i += stride) {
    const glm::vec3 m(map[i].mean.x(), map[i].mean.y(), map[i].mean.z());
    flat.emplace_back(glm::dot(m, a), glm::dot(m, b));
  }
  float angle = 0.f, best = INFINITY;
  std::vector<float> u(flat.size()), v(flat.size());
  const auto spread = [](std::vector<float>& x) {
    const std::size_t lo = x.size() * 2 / 100, hi = std::min(x.size() - 1, x.size() * 98 / 100);
    std::nth_element(x.begin(), x.begin() + static_cast<long>(lo), x.end());
    const float x_lo = x[lo];
    std::nth_element(x.begin(), x.begin() + static_cast<long>(hi), x.end());
    return x[hi] - x_lo;
  };
  for (int step = 0; step < 18 && flat.size() > 1; ++step) {
    const float t = glm::radians(5.f * static_cast<float>(step)), c = std::cos(t), sn = std::sin(t);
    for (std::size_t i = 0; i < flat.size(); ++i) {
      u[i] = c * flat[i].x + sn * flat[i].y;
      v[i] = -sn * flat[i].x + c * flat[i].y;
    }
    const float area = spread(u) * spread(v);
    if (area < best - 1e-9f) best = area, angle = t;
  }
  const glm::vec3 h1 = std::cos(angle) * a + std::sin(angle) * b;
  const glm::vec3 h2 = glm::cross(up, h1);
  return glm::mat3(h1, h2, up);
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

std::vector<Ellipsoid> slicedMap(std::span<const Ellipsoid> map, const HeightFrame& frame, const HeightSlice& slice) {
  std::vector<Ellipsoid> kept;
  for (const Ellipsoid& e : map)
    if (slice.keeps(frame.height({e.mean.x(), e.mean.y(), e.mean.z()}))) kept.push_back(e);
  return kept;
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

OrbitCamera defaultOrbit(const FrameBox& bounds, const glm::vec3& up, float aspect, float fov_y_deg,
                         Projection projection) {
  OrbitCamera cam = OrbitCamera::framing(bounds, up, aspect);
  if (fov_y_deg != cam.fov_y_deg || projection == Projection::kOrthographic) {
    cam.fov_y_deg = fov_y_deg;
    cam.orthographic = projection == Projection::kOrthographic;
    cam.frame(bounds, aspect);
  }
  return cam;
}

void presetView(OrbitCamera& cam, ViewPreset preset, const glm::mat3& axes) {
  const glm::vec3 h1 = axes[0], h2 = axes[1], up = axes[2];
  const float top = glm::radians(89.f);
  const glm::vec3 back = preset == ViewPreset::kTop     ? std::cos(top) * -h2 + std::sin(top) * up
                         : preset == ViewPreset::kFront ? -h2
                                                        : h1;
  const bool ortho = cam.orthographic;
  cam = OrbitCamera::fromLookAt(cam.target + cam.distance_m * back, cam.target, up, cam.fov_y_deg);
  cam.orthographic = ortho;
}

OrbitCamera orbitCamera(const ViewSpec& spec, const ViewScene& scene, int width, int height) {
  const bool ortho = spec.projection == Projection::kOrthographic;
  if (spec.look_at) {
    OrbitCamera cam =
        OrbitCamera::fromLookAt(spec.look_at->eye, spec.look_at->target, spec.look_at->up, spec.look_at->fov_y_deg);
    cam.orthographic = ortho;
    return cam;
  }
  const float aspect = static_cast<float>(width) / static_cast<float>(std::max(1, height));
  OrbitCamera cam = defaultOrbit(scene.bounds, scene.up, aspect, spec.fov_y_deg, spec.projection);
  if (spec.orbit) {
    cam.yaw = glm::radians(spec.orbit->azimuth_deg);
    const float limit = glm::radians(89.f);
    cam.pitch = std::clamp(glm::radians(spec.orbit->elevation_deg), -limit, limit);
    if (spec.orbit->distance_m) cam.distance_m = *spec.orbit->distance_m;
    else cam.fit(scene.bounds, aspect);  // framed from these angles
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
                               width, height, spec.projection == Projection::kOrthographic),
            {0, 0, width, height}};
  return {orbitCamera(spec, scene, width, height).view(width, height), {0, 0, width, height}};
}

}  // namespace vdmap::render
