#pragma once
// The global map's ellipsoids as surfaces for point, distance and ray queries (docs/method.md 13):
// each one's k-sigma gate (covariance + min_sigma^2 I), a grid for gate lookups and a box tree for
// nearest-surface and first-hit searches. QueryMap is the interface; the geometry code owns this.
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "mapping/query/ellipsoid_geometry.h"
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

  struct Nearest {
    std::int32_t ellipsoid = -1;
    double distance = std::numeric_limits<double>::infinity();
    Eigen::Vector3d closest = Eigen::Vector3d::Zero();
  };
  /// The nearest gate surface (distanceToGate): inside a gate, distance 0 and gate(q)'s ellipsoid;
  /// else the ellipsoid with the smallest (distance^2, index) over all ellipsoids, when distance^2 <
  /// max_distance^2 ({-1, inf} otherwise). Exact: a box tree over the gates' boxes.
  Nearest nearest(const Eigen::Vector3d& q_W, double max_distance = std::numeric_limits<double>::infinity()) const;

  struct Hit {
    std::int32_t ellipsoid = -1;
    double t = std::numeric_limits<double>::infinity();
  };
  /// The smallest (gateRayEntry, index) over all ellipsoids of the ray o + t d (d unit), t <= max_t
  /// (box tree, nearest node first).
  Hit firstHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t) const;

  /// What a ray's entry reads of ellipsoid i's gate: its mean, A and k^2 (the principal frame and
  /// box left at identity and zero: rebuilding the frame would cost a view's splats).
  EllipsoidGate rayGateOf(std::size_t i) const;
  /// gateNormal of ellipsoid i's gate at p, bit for bit, from its A and mean alone (a ray hit's
  /// normal).
  Eigen::Vector3d normalOf(std::size_t i, const Eigen::Vector3d& p) const;
  /// The gates are stored in Morton order of their means: the ellipsoid at storage rank r, and
  /// its gate (without its box: half_extent zero) and bounding ball (mean, longest semi-axis). A
  /// pass over every gate reads memory in order by rank, where one by ellipsoid index jumps.
  std::int32_t ellipsoidAtRank(std::size_t r) const;
  EllipsoidGate gateAtRank(std::size_t r) const;
  Eigen::Vector4d ballAtRank(std::size_t r) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace vdmap
