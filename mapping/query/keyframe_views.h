#pragma once
// Free space from the keyframes' own views (docs/method.md 13): per keyframe, its kept cells as
// Gaussians in the keyframe frame, and an index of which keyframes can see a world point.
// Internal to mapping/query (QueryMap is the interface). Owner: the classification code.
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "mapping/query/query_map.h"

namespace vdmap {

/// One keyframe's verdict about a point.
struct ViewVerdict {
  Occupancy state = Occupancy::kUnknown;  ///< kUnknown: the keyframe does not see it (or sees it behind its surface)
  double z = 0;                           ///< (|q| - t*) / sigma_t: < -k free, |.| small on the surface
  double sigma_t = 0;                     ///< the surface's sigma along the ray (m)
  double m2 = 0;                          ///< squared gate distance to the cell's ellipsoid (occupied)
};

class KeyframeViews {
 public:
  KeyframeViews() = default;
  static KeyframeViews build(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& params,
                             std::span<const int> keyframe_rank);
  std::size_t size() const;
  std::size_t memoryBytes() const;
  void seenBounds(Eigen::Vector3d* lo, Eigen::Vector3d* hi) const;
  /// Keyframe `id`'s verdict about world point q_W.
  ViewVerdict verdict(int id, const Eigen::Vector3d& q_W) const;
  /// The combined verdict of every keyframe under `params.conflict`, for a point no global gate holds
  /// (kOccupied) or for any point (kRecent, kPrecise); `keyframe` receives the deciding keyframe.
  ViewVerdict combined(const Eigen::Vector3d& q_W, int* keyframe) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace vdmap
