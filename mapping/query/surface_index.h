#pragma once
// The global map's ellipsoids as surfaces for point, distance and ray queries (docs/method.md 13):
// each one's k-sigma gate (covariance + min_sigma^2 I), a grid for gate lookups and a box tree for
// nearest-surface and first-hit searches. Internal to mapping/query (QueryMap is the interface).
// Owner: the geometry code.
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "mapping/query/query_map.h"

namespace vdmap {

class SurfaceIndex {
 public:
  SurfaceIndex() = default;
  static SurfaceIndex build(const std::vector<Ellipsoid>& ellipsoids_W, const QueryParams& params);
  std::size_t size() const;
  std::size_t memoryBytes() const;
  /// The ellipsoid whose gate holds q with the smallest squared gate distance m2 (ties: lower index),
  /// or {-1, inf} when no gate holds q.
  std::pair<std::int32_t, double> gate(const Eigen::Vector3d& q_W) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace vdmap
