#include "mapping/eval/mesh_accuracy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include "mapping/core/box_tree.h"

namespace vdmap {
namespace {

Eigen::Vector3d vertex(const ColoredTriangleMesh& mesh, std::size_t t, int k) {
  return mesh.positions[mesh.triangles[t][k]].cast<double>();
}

double sqDistToTriangle(const ColoredTriangleMesh& mesh, std::size_t t, const Eigen::Vector3d& q) {
  return (closestPointOnTriangle(q, vertex(mesh, t, 0), vertex(mesh, t, 1), vertex(mesh, t, 2)) - q).squaredNorm();
}

// out[i] = f(i) for every i, in parallel; each entry is independent, so the result is the same
// for any thread count.
template <typename F>
std::vector<double> parallelMap(std::size_t n, F&& f) {
  std::vector<double> out(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) { out[i] = f(i); });
  return out;
}

}  // namespace

Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // degenerate (zero-area) triangle: its vertices are as good
  const double v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

std::vector<double> distancesToMesh(const std::vector<Eigen::Vector3f>& points, const ColoredTriangleMesh& mesh) {
  const std::size_t n = mesh.triangles.size();
  std::vector<Eigen::Vector3f> lo(n), hi(n);
  for (std::size_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    lo[t] = mesh.positions[tri[0]].cwiseMin(mesh.positions[tri[1]]).cwiseMin(mesh.positions[tri[2]]);
    hi[t] = mesh.positions[tri[0]].cwiseMax(mesh.positions[tri[1]]).cwiseMax(mesh.positions[tri[2]]);
  }
  const BoxTree tree(lo, hi);
  return parallelMap(points.size(), [&](std::size_t i) {
    const auto sq = [&](std::uint32_t t, const Eigen::Vector3d& q) { return sqDistToTriangle(mesh, t, q); };
    return std::sqrt(tree.nearest(points[i].cast<double>(), sq).second);
  });
}

std::vector<double> distancesToMeshBruteForce(const std::vector<Eigen::Vector3f>& points,
                                              const ColoredTriangleMesh& mesh) {
  std::vector<double> out;
  for (const Eigen::Vector3f& p : points) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      best = std::min(best, sqDistToTriangle(mesh, t, p.cast<double>()));
    out.push_back(std::sqrt(best));
  }
  return out;
}

std::vector<double> distancesToPoints(const std::vector<Eigen::Vector3f>& queries,
                                      const std::vector<Eigen::Vector3f>& points) {
  const BoxTree tree(points, points);
  return parallelMap(queries.size(), [&](std::size_t i) {
    const auto sq = [&](std::uint32_t j, const Eigen::Vector3d& q) {
      return (points[j].cast<double>() - q).squaredNorm();
    };
    return std::sqrt(tree.nearest(queries[i].cast<double>(), sq).second);
  });
}

std::vector<Eigen::Vector3f> sampleMeshSurface(const ColoredTriangleMesh& mesh, std::size_t count, std::uint32_t seed,
                                               std::vector<std::uint32_t>* triangles) {
  if (triangles) triangles->clear();
  std::vector<double> cumulative_area(mesh.triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3d a = vertex(mesh, t, 0);
    total += 0.5 * (vertex(mesh, t, 1) - a).cross(vertex(mesh, t, 2) - a).norm();
    cumulative_area[t] = total;
  }
  std::vector<Eigen::Vector3f> out;
  if (total <= 0.0) return out;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double pick = uniform(rng) * total;
    const std::size_t t = std::min<std::size_t>(
        std::upper_bound(cumulative_area.begin(), cumulative_area.end(), pick) - cumulative_area.begin(),
        mesh.triangles.size() - 1);
    double r1 = uniform(rng), r2 = uniform(rng);
    if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;  // fold the square onto the triangle
    const Eigen::Vector3d a = vertex(mesh, t, 0);
    out.push_back((a + r1 * (vertex(mesh, t, 1) - a) + r2 * (vertex(mesh, t, 2) - a)).cast<float>());
    if (triangles) triangles->push_back(static_cast<std::uint32_t>(t));
  }
  return out;
}

AccuracyReport evaluateAccuracy(const std::vector<Eigen::Vector3f>& points, const ColoredTriangleMesh& mesh,
                                const AccuracyParams& params) {
  AccuracyReport r;
  r.elements = points.size();
  if (!points.empty()) {
    std::vector<double> d = distancesToMesh(points, mesh);
    double sum = 0.0, sum2 = 0.0;
    for (const double x : d) sum += x, sum2 += x * x;
    r.mean_mm = 1e3 * sum / d.size();
    r.rmse_mm = 1e3 * std::sqrt(sum2 / d.size());
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    double med = d[d.size() / 2];
    if (d.size() % 2 == 0) med = 0.5 * (med + *std::max_element(d.begin(), d.begin() + d.size() / 2));
    r.median_mm = 1e3 * med;
  }
  const std::vector<Eigen::Vector3f> samples = sampleMeshSurface(mesh, params.completion_samples, params.seed);
  if (samples.empty()) return r;
  if (points.empty()) {
    r.completion_mean_mm = std::numeric_limits<double>::infinity();
    return r;
  }
  const std::vector<double> c = distancesToPoints(samples, points);
  double sum = 0.0;
  std::size_t within = 0;
  for (const double x : c) sum += x, within += x <= params.completion_within_m;
  r.completion_mean_mm = 1e3 * sum / c.size();
  r.completion_ratio = static_cast<double>(within) / c.size();
  return r;
}

SurfaceAccuracyReport evaluateSurfaceAccuracy(const ColoredTriangleMesh& surface, const ColoredTriangleMesh& reference,
                                              const AccuracyParams& params, const std::vector<bool>& seen) {
  SurfaceAccuracyReport r;
  r.triangles = surface.triangles.size();
  if (surface.triangles.empty()) return r;
  std::vector<double> d =
      distancesToMesh(sampleMeshSurface(surface, params.completion_samples, params.seed), reference);
  double sum = 0.0, sum2 = 0.0;
  for (const double x : d) sum += x, sum2 += x * x;
  r.mean_mm = 1e3 * sum / d.size();
  r.rmse_mm = 1e3 * std::sqrt(sum2 / d.size());
  std::sort(d.begin(), d.end());
  r.median_mm = 1e3 * d[d.size() / 2];
  r.p95_mm = 1e3 * d[std::min(d.size() - 1, d.size() * 95 / 100)];
  const std::vector<double> c =
      distancesToMesh(sampleMeshSurface(reference, params.completion_samples, params.seed), surface);
  if (!seen.empty() && seen.size() != c.size()) throw std::invalid_argument("seen does not fit the reference samples");
  std::size_t within = 0, seen_count = 0, seen_within = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const bool near = c[i] <= params.completion_within_m, counted = seen.empty() || seen[i];
    within += near;
    seen_count += counted;
    seen_within += counted && near;
  }
  r.completion_ratio = c.empty() ? 0.0 : static_cast<double>(within) / c.size();
  r.seen_completion_ratio = seen_count ? static_cast<double>(seen_within) / seen_count : 0.0;
  return r;
}

}  // namespace vdmap
