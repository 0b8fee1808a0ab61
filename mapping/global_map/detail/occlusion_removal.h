#pragma once
// Occlusion removal (docs/method.md 6.3), the stage of buildGlobalMap after merging within groups
// (6.2) and before fusion across groups (7). Its public entry point, occludingEllipsoids over a
// vector, is declared in global_map.h.
#include <span>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "mapping/global_map/detail/global_map_helpers.h"
#include "mapping/global_map/global_map.h"

namespace vdmap::global_map_detail {

/// An ellipsoid as one occlusion viewpoint sees it.
struct ViewItem {
  double z;             ///< depth in the viewpoint's camera
  double lambda_max;    ///< largest eigenvalue of its covariance: smaller is more precise
  Eigen::Vector3d ray;  ///< mean - viewpoint centre, world frame
  int index;            ///< into the ellipsoids
};

/// What one occlusion viewpoint needs; one per thread, reused across viewpoints and builds (fresh
/// buffers cost a page fault per 4 KiB).
struct OcclusionScratch {
  /// A point of the viewpoint's group that falls into one of its cells. Most cells hold one point
  /// and are never judged, so this carries only what finds its cell's others.
  struct Seen {
    int cell;
    int j;  ///< into OcclusionBuffers' by-keyframe arrays
    double z;
  };
  std::vector<Seen> seen;
  std::vector<int> count, start, fill;  ///< per cell
  std::vector<ViewItem> items;          ///< the judged cells' (two or more points), cell by cell
  std::vector<double> finest;
};

/// Occlusion removal's buffers, reused across builds.
struct OcclusionBuffers {
  std::vector<int> keyframe_of, fill;
  Buckets by_keyframe;  ///< ellipsoid indices by keyframe; j indexes its order
  struct Point {
    Eigen::Vector3d mean;
    double lambda_max;
  };
  std::vector<Point> point;                  ///< by j
  std::vector<std::vector<int>> removed_by;  ///< per viewpoint, ellipsoid indices
  tbb::enumerable_thread_specific<OcclusionScratch> scratch;
};

/// Gives back the memory of `buffers` (a build that is not repeated).
void releaseOcclusionBuffers(OcclusionBuffers* buffers);

/// Occlusion removal (docs/method.md 6.3) of world-frame ellipsoids, lambda_max[i] being the largest
/// eigenvalue of ellipsoid i's floored covariance: removed[i] (resized to their number) is 1 when
/// ellipsoid i is removed. Every keyframe of `graph` is a viewpoint. The same answer for any
/// params.threads; one call per `buffers` at a time.
void occludingEllipsoids(const KeyframeGraph& graph, std::span<const Ellipsoid* const> ellipsoids,
                         const std::vector<double>& lambda_max, const GlobalMapParams& params,
                         OcclusionBuffers* buffers, std::vector<char>* removed);

}  // namespace vdmap::global_map_detail
