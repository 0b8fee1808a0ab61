// QueryMap's surface queries (docs/method.md 13.4-13.6): distance to the nearest k-sigma gate
// surface, collision of sphere bodies, first gate entry along rays and whole camera views.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "mapping/core/parallel.h"
#include "mapping/query/detail/query_map_data.h"
#include "mapping/query/ellipsoid_geometry.h"

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
  hit.normal_W = surface.normalOf(static_cast<std::size_t>(h.ellipsoid), hit.point_W);
  hit.ellipsoid = h.ellipsoid;
  return hit;
}

}  // namespace

void QueryMap::distance(std::span<const Eigen::Vector3d> q_W, std::span<DistanceResult> out,
                        double max_distance_m) const {
  checkSizes(q_W.size(), out.size());
  if (std::isnan(max_distance_m) || max_distance_m < 0) throw std::invalid_argument("max_distance_m must be >= 0");
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
      const Eigen::Vector3d away = q_W[i] - n.closest;
      if (n.distance > 0 && away.norm() > 0) r.gradient = away / away.norm();
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
  if (!data_ || data_->surface.size() == 0) return pixels;
  const SurfaceIndex& surface = data_->surface;
  const int threads = data_->params.threads;
  const Eigen::Vector3d o = T_W_C.translation();
  const Transform T_C_W = T_W_C.inverse();
  const Eigen::Matrix3d R_C_W = T_C_W.linear();

  // Rasterise instead of tracing (docs/method.md 13.6): each gate in front of the camera splats
  // over the exact image box of its silhouette (+1 px), where every pixel evaluates the same
  // gateRayEntry on the same pixelRay as castRays; a pixel keeps the smallest (t, index). Gates go
  // nearest first, so a pixel whose hit is nearer than a gate's nearest point skips that gate.
  // Inward unit normals of the frustum's side planes through the camera centre, 2 px outside the
  // image's outer pixel edges (camera frame).
  std::vector<Eigen::Vector3d> frustum_normals;
  {
    const double l = (-2.5 - camera.cx) / camera.fx, r = (camera.width + 1.5 - camera.cx) / camera.fx;
    const double t = (-2.5 - camera.cy) / camera.fy, b = (camera.height + 1.5 - camera.cy) / camera.fy;
    frustum_normals = {Eigen::Vector3d(1, 0, -l).normalized(), Eigen::Vector3d(-1, 0, r).normalized(),
                       Eigen::Vector3d(0, 1, -t).normalized(), Eigen::Vector3d(0, -1, b).normalized()};
  }
  const std::size_t n = surface.size();
  std::vector<std::pair<double, std::int32_t>> nearest(n, {0.0, -1});  // (t_lo, index); index -1: not in view
  std::vector<std::array<std::int16_t, 4>> box(n);                     // its image box
  parallelFor(threads, n, [&](std::size_t r) {  // in storage order (SurfaceIndex::ellipsoidAtRank)
    const std::size_t i = static_cast<std::size_t>(surface.ellipsoidAtRank(r));
    int u0, u1, v0, v1;
    // Cheap first: the gate's bounding ball behind the camera or outside a side of the frustum.
    const Eigen::Vector4d ball = surface.ballAtRank(r);
    const Eigen::Vector3d c = T_C_W * Eigen::Vector3d(ball.head<3>());
    const double radius = ball[3] * (1 + 1e-9) + 1e-9;
    if (c.z() + radius <= 0) return;
    for (const Eigen::Vector3d& n : frustum_normals)
      if (n.dot(c) < -radius) return;
    const EllipsoidGate g = surface.gateAtRank(r);
    if (!gateImageBounds(g, camera, T_C_W, 1.0, &u0, &u1, &v0, &v1)) return;
    box[i] = {static_cast<std::int16_t>(u0), static_cast<std::int16_t>(u1), static_cast<std::int16_t>(v0),
              static_cast<std::int16_t>(v1)};
    // No point of the gate is nearer to o (with slack for rounding).
    const double gap = (o - g.mean).norm() - g.semi_axes[0];
    nearest[i] = {gap > 0 ? gap * (1 - 1e-9) - 1e-9 : -1.0, static_cast<std::int32_t>(i)};
  });
  std::vector<std::pair<double, std::int32_t>> order;  // nearest first, no ties
  for (const auto& e : nearest)
    if (e.second >= 0) order.push_back(e);
  parallelSort(threads, order.begin(), order.end());

  // Everything a splat's pixels read, in that order (packed, computed once).
  struct Splat {
    double t_lo = 0;
    std::int32_t index = -1;
    int u0 = 0, u1 = -1, v0 = 0, v1 = -1;
    double a[6];  // the gate's A, upper triangle
    GateRayOrigin origin;
    // The silhouette's span per row (see below): w = R A (o - mean), B = R A R^T (upper), qa.
    Eigen::Vector3d w;
    double b[6];
    double qa = 0;
  };
  std::vector<Splat> splats(order.size());
  parallelFor(threads, order.size(), [&](std::size_t k) {
    const EllipsoidGate g = surface.rayGateOf(static_cast<std::size_t>(order[k].second));
    Splat& s = splats[k];
    s.t_lo = order[k].first;
    s.index = order[k].second;
    const auto& bx = box[static_cast<std::size_t>(s.index)];
    s.u0 = bx[0], s.u1 = bx[1], s.v0 = bx[2], s.v1 = bx[3];
    gateUpper(g, s.a);
    s.origin = gateRayOrigin(g, o);
    s.w = R_C_W * s.origin.A_oc;
    const Eigen::Matrix3d B = R_C_W * g.A * R_C_W.transpose();
    const double b[6] = {B(0, 0), B(1, 1), B(2, 2), B(0, 1), B(0, 2), B(1, 2)};
    std::copy(b, b + 6, s.b);
    s.qa = s.w.x() * s.w.x() - s.origin.gamma * B(0, 0);
  });

  // Row tiles; per tile the splats that reach it, nearest first.
  constexpr int kTileRows = 16;
  const std::size_t tiles = (height + kTileRows - 1) / kTileRows;
  std::vector<std::size_t> tile_start(tiles + 1, 0);
  for (const Splat& s : splats)
    for (int t = s.v0 / kTileRows; t <= s.v1 / kTileRows; ++t) ++tile_start[static_cast<std::size_t>(t) + 1];
  for (std::size_t t = 0; t < tiles; ++t) tile_start[t + 1] += tile_start[t];
  std::vector<std::uint32_t> tile_splats(tile_start[tiles]);
  {
    std::vector<std::size_t> fill(tile_start.begin(), tile_start.end() - 1);
    for (std::size_t k = 0; k < splats.size(); ++k)
      for (int t = splats[k].v0 / kTileRows; t <= splats[k].v1 / kTileRows; ++t)
        tile_splats[fill[static_cast<std::size_t>(t)]++] = static_cast<std::uint32_t>(k);
  }

  parallelFor(threads, tiles, [&](std::size_t tile) {
    const int row0 = static_cast<int>(tile) * kTileRows;
    const int row1 = std::min(static_cast<int>(height), row0 + kTileRows) - 1;
    const std::size_t tile_pixels = static_cast<std::size_t>(row1 - row0 + 1) * width;
    std::vector<Eigen::Vector3d> dir(tile_pixels);
    std::vector<double> best_t(tile_pixels, std::numeric_limits<double>::infinity());
    std::vector<std::int32_t> best_i(tile_pixels, -1);
    for (int v = row0; v <= row1; ++v)
      for (std::size_t u = 0; u < width; ++u)
        dir[static_cast<std::size_t>(v - row0) * width + u] =
            unitDirection(pixelRay(camera, T_W_C, static_cast<int>(u), v));
    double farthest = std::numeric_limits<double>::infinity();  // max best_t over the tile (refreshed)
    for (std::size_t k = tile_start[tile]; k < tile_start[tile + 1]; ++k) {
      if (k + 4 < tile_start[tile + 1]) __builtin_prefetch(&splats[tile_splats[k + 4]]);
      const Splat& s = splats[tile_splats[k]];
      // Splats come nearest first: once one starts beyond every pixel's hit, so do the rest, and
      // every pixel would skip them.
      if ((k - tile_start[tile]) % 256 == 255) farthest = *std::max_element(best_t.begin(), best_t.end());
      if (s.t_lo > farthest) break;
      // Per row, only the pixels whose rays can reach the gate: with r = R_C_W d = (x, y, 1) up to
      // scale, gateRayEntry's discriminant (r.w)^2 - gamma r^T B r is a quadratic in x that is
      // >= 0 on the silhouette's span of the row. Extra pixels only cost time (each still
      // evaluates the exact entry), so the span is grown by 2 px.
      const Eigen::Vector3d& w = s.w;
      const double gamma = s.origin.gamma, qa = s.qa, inv_qa = 1.0 / qa;
      for (int v = std::max(s.v0, row0); v <= std::min(s.v1, row1); ++v) {
        const std::size_t row = static_cast<std::size_t>(v - row0) * width;
        int ua = s.u0, ub = s.u1;
        if (gamma > 0 && qa < 0) {
          const double y = (v - camera.cy) / camera.fy, wy = w.y() * y + w.z();
          const double qb = w.x() * wy - gamma * (s.b[3] * y + s.b[4]);
          const double qc = wy * wy - gamma * (s.b[1] * y * y + 2.0 * s.b[5] * y + s.b[2]);
          const double disc = qb * qb - qa * qc;
          const double r = disc > 0 ? std::sqrt(disc) : 0.0;  // no span: the vertex, in case of rounding
          const double x_lo = (-qb + r) * inv_qa, x_hi = (-qb - r) * inv_qa;  // qa < 0
          const double p_lo = camera.cx + camera.fx * x_lo - 2.0, p_hi = camera.cx + camera.fx * x_hi + 2.0;
          if (p_lo <= p_hi) {  // (not NaN)
            if (p_lo > ua) ua = p_lo > ub ? ub + 1 : static_cast<int>(std::floor(p_lo));
            if (p_hi < ub) ub = p_hi < ua ? ua - 1 : static_cast<int>(std::ceil(p_hi));
          }
        }
        for (int u = ua; u <= ub; ++u) {
          const std::size_t p = row + static_cast<std::size_t>(u);
          const double bt = best_t[p];
          if (bt < s.t_lo) continue;
          const double t = gateRayEntry(s.a, s.origin, dir[p], std::min(bt, max_range_m));
          if (t < bt || (t == bt && t <= max_range_m && s.index < best_i[p])) best_t[p] = t, best_i[p] = s.index;
        }
      }
    }
    // makeHit's answers. Neighbouring pixels mostly hit the same gate: its A and mean are read
    // once per run of it (rayGateOf's are normalOf's, so the normals are castRays' bit for bit).
    std::int32_t last = -1;
    EllipsoidGate g;
    for (int v = row0; v <= row1; ++v)
      for (std::size_t u = 0; u < width; ++u) {
        const std::size_t p = static_cast<std::size_t>(v - row0) * width + u;
        const std::int32_t i = best_i[p];
        if (i < 0) continue;
        if (i != last) g = surface.rayGateOf(static_cast<std::size_t>(i)), last = i;
        RayHit& hit = pixels[static_cast<std::size_t>(v) * width + u];
        hit.hit = true;
        hit.t_m = best_t[p];
        hit.point_W = o + hit.t_m * dir[p];
        hit.normal_W = gateNormal(g, hit.point_W);
        hit.ellipsoid = i;
      }
  });
  return pixels;
}

}  // namespace vdmap
