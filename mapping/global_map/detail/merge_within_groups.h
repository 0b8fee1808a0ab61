#pragma once
// Merging within a merge group (docs/method.md 6.2), the stage of buildGlobalMap between the
// groups (6.1) and occlusion removal (6.3). Its public pieces (meanShiftClusters, momentMatch)
// are declared in global_map.h.
#include <vector>

#include "mapping/global_map/detail/global_map_helpers.h"
#include "mapping/global_map/global_map.h"

namespace vdmap::global_map_detail {

/// What merging one group needs besides its output; one per thread, reused across groups and
/// builds (fresh buffers cost a page fault per 4 KiB).
struct MergeScratch {
  struct Source {
    int member;      ///< index into group.members
    int cell_index;  ///< into that keyframe's container cells()
  };
  std::vector<Transform> T_C_K;
  std::vector<Source> sources;
  std::vector<int> cell_of, fill, label;
  Buckets by_cell;
  std::vector<Ellipsoid> in_cell;
  std::vector<Eigen::Vector3d> means;
  std::vector<double> weights;
  std::vector<const Ellipsoid*> cluster;
};

/// docs/method.md 6.2 for one group: the members' kept ellipsoids (`kept`, per keyframe id)
/// re-projected into the centre's container and merged cell by cell, into `out` (replacing what it
/// held), in the world frame. Output order: cells ascending, then the ellipsoids that fall into no
/// cell of the centre, which pass through. Reads the graph only; one call per scratch at a time.
void mergeGroup(const KeyframeGraph& graph, const MergeGroup& group, const GlobalMapParams& params,
                const std::vector<std::vector<bool>>& kept, MergeScratch* scratch, std::vector<Ellipsoid>* out);

}  // namespace vdmap::global_map_detail
