#include "app/bench/query_detail.h"

#include <cstdio>

#include "mapping/core/timing.h"
#include "mapping/query/ellipsoid_geometry.h"

namespace vdmap::app {
namespace {

const char* ruleName(ConflictRule rule) {
  return rule == ConflictRule::kOccupied ? "occupied" : rule == ConflictRule::kRecent ? "recent" : "precise";
}

double perSecond(std::size_t n, double ms) { return ms > 0 ? 1e3 * static_cast<double>(n) / ms : 0.0; }

// Bit for bit the same answer (castView promises castRays' answers on its pixel rays).
bool same(const RayHit& a, const RayHit& b) {
  return a.hit == b.hit && a.t_m == b.t_m && a.ellipsoid == b.ellipsoid && a.normal_W == b.normal_W;
}

}  // namespace

nlohmann::json timeQueryDetail(const QueryDetailInput& in, std::ostringstream* text) {
  char buf[512];
  nlohmann::json out;
  const std::size_t n = in.points.size();
  *text << "\nvdmap alone (one thread, process CPU, median of " << in.passes << " passes):\n";
  std::snprintf(buf, sizeof buf, "%-16s %14s %9s %8s %8s\n", "conflict rule", "classify [/s]", "occupied", "free",
                "unknown");
  *text << buf;
  for (const ConflictRule rule : {ConflictRule::kOccupied, ConflictRule::kRecent, ConflictRule::kPrecise}) {
    std::vector<Classification> other;
    double ms = in.classify_ms;
    std::span<const Classification> classes = in.classified;
    if (rule != ConflictRule::kOccupied) {
      QueryParams params = in.query.params();
      params.conflict = rule;
      const QueryMap map = QueryMap::build(in.graph, in.global, params);
      other.resize(n);
      ms = medianCpuTimeMs(in.passes, [&] { map.classify(in.points, other); });
      classes = other;
    }
    std::size_t count[3] = {0, 0, 0};  // by Occupancy: unknown, free, occupied
    for (const Classification& c : classes) ++count[static_cast<int>(c.state)];
    double share[3];
    for (int k = 0; k < 3; ++k) share[k] = static_cast<double>(count[k]) / static_cast<double>(n);
    std::snprintf(buf, sizeof buf, "%-16s %14.0f %9.3f %8.3f %8.3f\n", ruleName(rule), perSecond(n, ms), share[2],
                  share[1], share[0]);
    *text << buf;
    out["classify_by_rule"][ruleName(rule)] = {{"classify_ms", rounded(ms)},
                                               {"classify_per_s", rounded(perSecond(n, ms))},
                                               {"occupied", rounded(share[2])},
                                               {"free", rounded(share[1])},
                                               {"unknown", rounded(share[0])}};
  }

  // The speed points alternate uniform in the seen box (even) and near surfaces (odd).
  std::vector<Eigen::Vector3d> half[2];
  for (std::size_t i = 0; i < in.distance_points.size(); ++i) half[i % 2].push_back(in.distance_points[i]);
  double half_per_s[2] = {0, 0};
  for (int h = 0; h < 2; ++h) {
    std::vector<DistanceResult> d(half[h].size());
    half_per_s[h] = perSecond(half[h].size(), medianCpuTimeMs(in.passes, [&] { in.query.distance(half[h], d); }));
  }
  std::snprintf(buf, sizeof buf, "distance [/s]: near surfaces %.0f, uniform in the seen box %.0f\n", half_per_s[1],
                half_per_s[0]);
  *text << buf;
  out["distance_near_per_s"] = rounded(half_per_s[1]);
  out["distance_uniform_per_s"] = rounded(half_per_s[0]);

  if (!in.views.empty()) {
    const Transform& T_W_C = in.views.front();
    std::vector<Ray> rays;
    for (int v = 0; v < in.camera.height; ++v)
      for (int u = 0; u < in.camera.width; ++u)
        rays.push_back({T_W_C.translation(), pixelRay(in.camera, T_W_C, u, v), in.max_range_m});
    std::vector<RayHit> hits(rays.size());
    const double ms = medianCpuTimeMs(in.passes, [&] { in.query.castRays(rays, hits); });
    const std::vector<RayHit> view = in.query.castView(in.camera, T_W_C, in.max_range_m);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) differ += !same(view[i], hits[i]);
    std::snprintf(buf, sizeof buf,
                  "castRays [/s]: %.0f on the first view's %zu pixel rays; castView gives the same answers: %s (%zu "
                  "differ)\n",
                  perSecond(rays.size(), ms), rays.size(), differ == 0 ? "yes" : "NO", differ);
    *text << buf;
    out["rays"] = rays.size();
    out["rays_per_s"] = rounded(perSecond(rays.size(), ms));
    out["view_rays_differ"] = differ;
  }

  const QueryMap::MemoryParts parts = in.query.memoryParts();
  const auto mb = [](std::size_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0); };
  std::snprintf(buf, sizeof buf,
                "QueryMap memory [MB]: %.1f (keyframe views %.1f, frames' free space %.1f, surface index %.1f)\n",
                mb(in.query.memoryBytes()), mb(parts.keyframe_views), mb(parts.frames), mb(parts.surface));
  *text << buf;
  out["memory_bytes"] = {{"total", in.query.memoryBytes()},
                         {"keyframe_views", parts.keyframe_views},
                         {"frames", parts.frames},
                         {"surface", parts.surface}};
  return out;
}

}  // namespace vdmap::app
