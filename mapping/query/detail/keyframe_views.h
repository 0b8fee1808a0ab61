#pragma once
// Free space from the keyframes' own views (docs/method.md 13): per keyframe, its kept cells as
// Gaussians in the keyframe frame, and an index of which keyframes can see a world point; and
// the free space of the frames integrated into them, with an index of its own.
// QueryMap is the interface; the classification code owns this.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "mapping/query/query_map.h"

namespace vdmap {

/// A kept cell's mean (keyframe frame) as the views store it: its z, and its ray's tangents
/// rounded to 1/32768 of a grid cell (0.7 um at 3 m with 8 px cells and a 525 px focal length).
Eigen::Vector3d storedViewMean(const KeyframeContainer& container, const StoredCell& cell);

/// Immutable after build; const methods are thread-safe. A copy shares the built data.
class KeyframeViews {
 public:
  KeyframeViews() = default;
  /// Per keyframe of `graph` at its current pose, the cells `global.kept` keeps. `keyframe_rank`
  /// (empty: ids) orders keyframes for ConflictRule::kRecent. Throws std::invalid_argument when
  /// `global` was not built from `graph` or keyframe_rank has the wrong size.
  static KeyframeViews build(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& params,
                             std::span<const int> keyframe_rank);
  std::size_t size() const;
  std::size_t memoryBytes() const;       ///< the keyframes' views and their index
  std::size_t frameMemoryBytes() const;  ///< the integrated frames' free space and its index
  /// Box of every keyframe's frustum cut at its farthest gate (lo > hi when nothing is seen).
  void seenBounds(Eigen::Vector3d* lo, Eigen::Vector3d* hi) const;
  /// Keyframe `id`'s verdict about world point q_W (docs/method.md 13.1).
  ViewVerdict verdict(int id, const Eigen::Vector3d& q_W) const;
  /// What keyframe `id`'s local map says: verdict(), else free when one of the frames integrated
  /// into it saw q_W free (docs/method.md 13.2).
  ViewVerdict localMapVerdict(int id, const Eigen::Vector3d& q_W) const;
  /// The combined verdict of the keyframes that may see q_W under `params.conflict`:
  /// kOccupied: the first keyframe (ascending id) whose verdict is free, else unknown (only
  /// called for points no global gate holds); kRecent: the verdict of the highest-ranked keyframe
  /// that has one; kPrecise: the verdict with the smallest sigma_t. Ties: lower id. When no
  /// keyframe has a verdict, free when an integrated frame saw q_W free (the first frame's
  /// keyframe decides). `keyframe` receives the deciding keyframe (-1 when unknown).
  ViewVerdict combined(const Eigen::Vector3d& q_W, int* keyframe) const;
  /// The keyframes that may see q_W (a superset of those with a verdict), ascending ids; under
  /// kRecent by rank, highest first (ties: lower id).
  std::span<const std::int32_t> candidates(const Eigen::Vector3d& q_W) const;

  struct Impl;

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace vdmap
