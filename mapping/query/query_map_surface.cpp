// QueryMap's surface queries (docs/method.md 13.4-13.6): distance to the nearest k-sigma gate
// surface, collision of sphere bodies, first gate entry along rays and whole camera views.
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "mapping/core/parallel.h"
#include "mapping/query/ellipsoid_geometry.h"
#include "mapping/query/query_map_data.h"

namespace vdmap {

namespace {

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

[[noreturn]] void badInput(const char* what, std::size_t index, const char* expected) {
  throw std::invalid_argument(std::string(what) + " " + std::to_string(index) + ": " + expected);
}

void checkSizes(std::size_t in, std::size_t out) {
  if (in != out)
    throw std::invalid_argument("query output holds " + std::to_string(out) + " entries for " + std::to_string(in) +
                                " inputs");
}

RayHit makeHit(const SurfaceIndex& surface, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
               const SurfaceIndex::Hit& h) {
  RayHit hit;
  if (h.ellipsoid < 0) return hit;
  hit.hit = true;
  hit.t_m = h.t;
  hit.point_W = o + h.t * d;
  hit.normal_W = gateNormal(surface.gateOf(static_cast<std::size_t>(h.ellipsoid)), hit.point_W);
  hit.ellipsoid = h.ellipsoid;
  return hit;
}

}  // namespace

void QueryMap::distance(std::span<const Eigen::Vector3d> q_W, std::span<DistanceResult> out,
                        double max_distance_m) const {
  checkSizes(q_W.size(), out.size());
  if (std::isnan(max_distance_m) || max_distance_m < 0)
    throw std::invalid_argument("max_distance_m must be >= 0");
  for (std::size_t i = 0; i < q_W.size(); ++i)
    if (!finite(q_W[i])) badInput("point", i, "expected finite coordinates");
  if (!data_) {
    std::fill(out.begin(), out.end(), DistanceResult{});
    return;
  }
  const SurfaceIndex& surface = data_->surface;
  parallelFor(data_->params.threads, q_W.size(), [&](std::size_t i) {
    const SurfaceIndex::Nearest n = surface.nearest(q_W[i], max_distance_m);
    DistanceResult r;
    r.distance_m = n.distance;
    r.ellipsoid = n.ellipsoid;
    if (n.ellipsoid >= 0) {
      r.closest_W = n.closest;
      if (n.distance > 0) r.gradient = (q_W[i] - n.closest) / (q_W[i] - n.closest).norm();
    }
    out[i] = r;
  });
}

std::vector<BodyCollision> QueryMap::collide(std::span<const Sphere> spheres, double clearance_m) const {
  if (!(clearance_m >= 0) || !std::isfinite(clearance_m))
    throw std::invalid_argument("clearance must be a finite number >= 0");
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    if (!finite(spheres[i].centre_W)) badInput("sphere", i, "expected a finite centre");
    if (!(spheres[i].radius_m > 0) || !std::isfinite(spheres[i].radius_m))
      badInput("sphere", i, "expected a finite radius > 0");
  }
  std::vector<Eigen::Vector3d> centres(spheres.size());
  for (std::size_t i = 0; i < spheres.size(); ++i) centres[i] = spheres[i].centre_W;
  std::vector<DistanceResult> dist(spheres.size());
  distance(centres, dist);

  // 15 probe points per sphere (docs/method.md 13.5): the centre, 6 along the axes and 8 along the
  // diagonals, at radius + clearance.
  constexpr int kProbes = 15;
  std::vector<Eigen::Vector3d> probes(spheres.size() * kProbes);
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const double r = spheres[i].radius_m + clearance_m, rd = r / std::sqrt(3.0);
    Eigen::Vector3d* p = &probes[i * kProbes];
    int j = 0;
    p[j++] = centres[i];
    for (int axis = 0; axis < 3; ++axis)
      for (const double s : {-1.0, 1.0}) p[j++] = centres[i] + s * r * Eigen::Vector3d::Unit(axis);
    for (const double sx : {-1.0, 1.0})
      for (const double sy : {-1.0, 1.0})
        for (const double sz : {-1.0, 1.0}) p[j++] = centres[i] + rd * Eigen::Vector3d(sx, sy, sz);
  }
  std::vector<Classification> classes(probes.size());
  classify(probes, classes);

  std::map<int, BodyCollision> bodies;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    BodyCollision& b = bodies.try_emplace(spheres[i].body).first->second;
    b.body = spheres[i].body;
    const double c = dist[i].distance_m - spheres[i].radius_m;
    if (c < b.clearance_m) b.clearance_m = c, b.sphere = static_cast<int>(i), b.closest_W = dist[i].closest_W;
    if (c < clearance_m) b.collides = true;
    for (int j = 0; j < kProbes; ++j)
      if (classes[i * kProbes + j].state == Occupancy::kUnknown) b.touches_unknown = true;
  }
  std::vector<BodyCollision> result;
  result.reserve(bodies.size());
  for (auto& [body, b] : bodies) result.push_back(b);
  return result;
}

void QueryMap::castRays(std::span<const Ray> rays, std::span<RayHit> out) const {
  checkSizes(rays.size(), out.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!finite(rays[i].origin_W)) badInput("ray", i, "expected a finite origin");
    if (!finite(rays[i].direction_W) || rays[i].direction_W.squaredNorm() == 0 ||
        !std::isfinite(rays[i].direction_W.norm()))
      badInput("ray", i, "expected a finite non-zero direction");
    if (!(rays[i].max_range_m >= 0)) badInput("ray", i, "expected a maximum range >= 0");
  }
  if (!data_) {
    std::fill(out.begin(), out.end(), RayHit{});
    return;
  }
  const SurfaceIndex& surface = data_->surface;
  parallelFor(data_->params.threads, rays.size(), [&](std::size_t i) {
    const Eigen::Vector3d& o = rays[i].origin_W;
    const Eigen::Vector3d d = unitDirection(rays[i].direction_W);
    out[i] = makeHit(surface, o, d, surface.firstHit(o, d, rays[i].max_range_m));
  });
}

std::vector<RayHit> QueryMap::castView(const PinholeCamera& camera, const Transform& T_W_C, double max_range_m) const {
  camera.validate();
  if (!isValidTransform(T_W_C)) throw std::invalid_argument("camera pose: expected a finite rigid transform");
  if (!(max_range_m >= 0)) throw std::invalid_argument("maximum range: expected a number >= 0");
  const std::size_t width = static_cast<std::size_t>(camera.width), height = static_cast<std::size_t>(camera.height);
  std::vector<RayHit> pixels(width * height);
  if (!data_) return pixels;
  const SurfaceIndex& surface = data_->surface;
  const Eigen::Vector3d o = T_W_C.translation();
  parallelFor(data_->params.threads, height, [&](std::size_t v) {
    for (std::size_t u = 0; u < width; ++u) {
      const Eigen::Vector3d d = unitDirection(pixelRay(camera, T_W_C, static_cast<int>(u), static_cast<int>(v)));
      pixels[v * width + u] = makeHit(surface, o, d, surface.firstHit(o, d, max_range_m));
    }
  });
  return pixels;
}

}  // namespace vdmap
