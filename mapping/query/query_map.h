#pragma once
// Point queries a planner asks of the view-dependent map (docs/method.md 13): is a point occupied,
// free or unknown; how far is it from the nearest surface; does a body of spheres collide; where
// does a ray first meet a surface. Nothing is voxelised: occupied is the global map's ellipsoids'
// gates, free is what some keyframe sees in front of its measured surface by more than that
// surface's spread along the ray (where no keyframe sees, what a frame integrated into one saw in
// front of its depth), unknown is what nothing saw. Local maps live in their
// keyframes' frames, so a map whose poses were corrected answers with the corrected poses after
// QueryMap::build, without re-integration.
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"
#include "mapping/global_map/global_map.h"
#include "mapping/keyframe/keyframe_graph.h"

namespace vdmap {

enum class Occupancy : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };
/// "unknown", "free", "occupied".
const char* occupancyName(Occupancy state);

/// What decides a point that one keyframe sees free and another sees occupied (a moved object;
/// docs/method.md 13).
enum class ConflictRule : std::uint8_t {
  kOccupied,  ///< inside any global ellipsoid's gate is occupied (safe; agrees with distance 0)
  kRecent,    ///< the keyframe observed last decides (a box taken away disappears once seen through)
  kPrecise,   ///< the keyframe whose surface along the ray is most precise (smallest sigma) decides
};

struct QueryParams {
  static constexpr double kMaxGateSigma = 100.0;  ///< gate_sigma lies in (0, kMaxGateSigma]
  static constexpr double kMaxMinSigmaM = 1.0;    ///< min_sigma_m lies in (0, kMaxMinSigmaM] m
  double gate_sigma = 3.0;     ///< k: occupied within k sigma of an ellipsoid; free more than k sigma in front
  double min_sigma_m = 0.001;  ///< added as min_sigma^2 I to every covariance before it is inverted
  ConflictRule conflict = ConflictRule::kOccupied;
  int threads = 0;  ///< 0: all cores; the answers do not depend on it
  /// Throws std::invalid_argument naming the first parameter out of range.
  void validate() const;
};

struct Classification {
  Occupancy state = Occupancy::kUnknown;
  /// Monotone in the classes: < 0.5 free, 0.5 unknown, > 0.5 occupied (docs/method.md 13).
  float p_occupied = 0.5f;
  std::int32_t keyframe = -1;   ///< the keyframe whose view decided (free, or occupied in a single keyframe)
  std::int32_t ellipsoid = -1;  ///< the global ellipsoid whose gate holds the point (occupied)
};

struct DistanceResult {
  /// Euclidean distance (m) to the nearest ellipsoid's k-sigma surface; 0 inside a gate; +inf on
  /// an empty map (or beyond max_distance_m: then "at least max_distance_m").
  double distance_m = std::numeric_limits<double>::infinity();
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();   ///< unit, away from the surface; 0 inside a gate
  Eigen::Vector3d closest_W = Eigen::Vector3d::Zero();  ///< the nearest surface point (the point itself inside a gate)
  std::int32_t ellipsoid = -1;                          ///< index into the global map's ellipsoids
};

struct Sphere {
  Eigen::Vector3d centre_W = Eigen::Vector3d::Zero();
  double radius_m = 0;
  int body = 0;  ///< spheres with the same body number form one body (a sphere-swept arm)
};

struct BodyCollision {
  int body = 0;
  bool collides = false;         ///< some sphere comes closer than its radius + clearance to a surface
  bool touches_unknown = false;  ///< some sphere's probe points (docs/method.md 13) lie in unknown space
  double clearance_m = std::numeric_limits<double>::infinity();  ///< min over spheres of distance - radius
  int sphere = -1;                                      ///< index (into the input) of the sphere that gave clearance_m
  Eigen::Vector3d closest_W = Eigen::Vector3d::Zero();  ///< that sphere's nearest surface point
};

struct Ray {
  Eigen::Vector3d origin_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction_W = Eigen::Vector3d::UnitZ();  ///< any length > 0; normalised by the query
  double max_range_m = 8.0;
};

struct RayHit {
  bool hit = false;
  double t_m = std::numeric_limits<double>::infinity();  ///< range along the unit direction
  Eigen::Vector3d point_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_W = Eigen::Vector3d::Zero();  ///< the gate surface's outward normal at the hit
  std::int32_t ellipsoid = -1;
};

/// One keyframe's verdict about a point (docs/method.md 13.1).
struct ViewVerdict {
  Occupancy state = Occupancy::kUnknown;  ///< kUnknown: the keyframe does not see it (or sees it behind its surface)
  double z = 0;                           ///< (|q| - t*) / sigma_t of the point's own cell: < -k free
  double sigma_t = 0;                     ///< the deciding cell's sigma along the ray (m)
  double m2 = 0;                          ///< squared gate distance to the nearest of the 3x3 cells (occupied)
};

/// Immutable after build(): every method is const and safe to call from many threads at once; a
/// copy shares the built data. Batched calls run on params.threads threads and give the same
/// answers for any thread count (each answer depends on its input alone).
class QueryMap {
 public:
  QueryMap();  ///< the empty map: unknown everywhere, no surface

  /// The queries over `global` (built from `graph` at the graph's current poses) and the local maps
  /// `global.kept` says were kept. Copies what it needs: the result outlives graph and map.
  /// `keyframe_rank[id]` orders keyframes by when they were last observed, for ConflictRule::kRecent
  /// (empty: by id). Throws std::invalid_argument for bad params or a map not built from this graph.
  static QueryMap build(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& params,
                        std::span<const int> keyframe_rank = {});

  const QueryParams& params() const;
  bool empty() const;  ///< no keyframe and no ellipsoid: every answer is unknown / no surface
  std::size_t keyframes() const;
  std::size_t ellipsoids() const;
  std::size_t memoryBytes() const;  ///< heap bytes held by the built data
  /// Heap bytes of the built data's parts: the keyframes' views and the integrated frames' free
  /// space (what free is), and the surface index of the global map's ellipsoids (occupied gates,
  /// distance, rays). memoryBytes() is their sum plus the parameters.
  struct MemoryParts {
    std::size_t keyframe_views = 0, frames = 0, surface = 0;
  };
  MemoryParts memoryParts() const;
  /// Axis-aligned box of everything some keyframe sees (its frusta cut at their farthest surface);
  /// lo > hi when empty. Where grids and slices are laid out.
  void seenBounds(Eigen::Vector3d* lo, Eigen::Vector3d* hi) const;

  /// Throw std::invalid_argument for a non-finite point (naming its index).
  void classify(std::span<const Eigen::Vector3d> q_W, std::span<Classification> out) const;
  /// The paper's arm-planning case: what keyframe `keyframe`'s local map alone says (its own cells,
  /// occupied within their gates, free in front of them or in front of what a frame integrated
  /// into it measured, unknown elsewhere).
  void classifyInKeyframe(int keyframe, std::span<const Eigen::Vector3d> q_W, std::span<Classification> out) const;
  /// The same verdict with its terms, for diagnostics: the depth relative to the surface of the
  /// point's own cell (sigma_t > 0 when the keyframe has a kept cell at the point's pixel).
  ViewVerdict keyframeVerdict(int keyframe, const Eigen::Vector3d& q_W) const;
  void distance(std::span<const Eigen::Vector3d> q_W, std::span<DistanceResult> out,
                double max_distance_m = std::numeric_limits<double>::infinity()) const;
  /// One entry per body, in ascending body number. Throws for radius <= 0 or clearance < 0.
  std::vector<BodyCollision> collide(std::span<const Sphere> spheres, double clearance_m) const;
  /// Throws for a zero or non-finite direction.
  void castRays(std::span<const Ray> rays, std::span<RayHit> out) const;
  /// One ray per pixel (row-major, width x height) through pixel centres of `camera` at pose T_W_C;
  /// the same answers as castRays on those rays.
  std::vector<RayHit> castView(const PinholeCamera& camera, const Transform& T_W_C, double max_range_m) const;

  struct Data;  // the built data (query_map.cpp)

 private:
  std::shared_ptr<const Data> data_;
};

}  // namespace vdmap
