#pragma once
// The global map (docs/method.md 6): a pure function of the local maps, their poses and the
// parameters, rebuilt whenever a threshold or a keyframe pose changes. One file per stage
// (global_map.cpp, which runs them, says which).
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap {

/// The live parameters of the global map (docs/parameters.md). Their ranges, units and help texts are
/// rows of the parameter table (global_map_parameters.cpp, docs/parameters.md).
struct GlobalMapParams {
  FilterParams filter;             ///< which local-map ellipsoids are kept
  double tau_group = 0.1;          ///< edge weight that puts a neighbour in a merge group
  double merge_distance_m = 0.25;  ///< mean-shift kernel radius h
  bool occlusion_removal = true;
  double occlusion_distance_m = 0.5;
  double occlusion_angle_deg = 30.0;
  /// docs/method.md 7: after merging and occlusion removal, fuse ellipsoids of different merge groups
  /// that describe the same surface, so the map grows with the area seen rather than with revisits.
  bool fuse_across_groups = true;
  /// Two ellipsoids of different groups are the same surface when their Bhattacharyya distance
  /// (bhattacharyyaDistance) is at most this.
  double fusion_max_distance = 1.0;
  int threads = 0;  ///< 0: all cores; at most kMaxThreads. The result does not depend on it.
  /// Throws std::invalid_argument naming the first parameter out of range (the table's ranges,
  /// and threads within 0..kMaxThreads).
  void validate() const;
};

/// A merge group: a centre keyframe and the neighbours re-projected into it.
struct MergeGroup {
  int centre = -1;
  std::vector<int> members;  ///< includes the centre, ascending ids
};

struct GlobalMap {
  /// World frame. keyframe: the group centre for merged clusters, else the ellipsoid's own.
  std::vector<Ellipsoid> ellipsoids;
  std::vector<MergeGroup> groups;
  /// Per keyframe id, which container cells passed the filter (keptCells): with
  /// forEachKeptEllipsoid, the local maps this map was built from, without filtering again.
  std::vector<std::vector<bool>> kept;
  std::size_t sigma_e = 0;               ///< ellipsoids kept in the local maps
  std::size_t merged = 0;                ///< after merging within groups, before occlusion removal and fusion
  std::size_t merged_across_groups = 0;  ///< ellipsoids fused into one of another group (docs/method.md 7)
  std::size_t sigma_e_prime = 0;         ///< after merging, occlusion removal and fusion
  double t_g_s = 0;                      ///< wall time of grouping, merging, occlusion removal and fusion
  double groups_ms = 0, merge_ms = 0, fusion_ms = 0, occlusion_ms = 0;
  /// What this build took over from the previous build with the same GlobalMapWorkspace instead
  /// of computing it again (all zero without a workspace). The map is the same either way.
  struct Reuse {
    bool groups = false;            ///< the merge groups came out as before (they are always recomputed: microseconds)
    std::size_t merged_groups = 0;  ///< groups whose merge was kept: same members, kept cells, poses and merge distance
    bool occlusion = false;         ///< occlusion removal skipped: same merged ellipsoids, poses, edges and parameters
    bool fusion = false;            ///< fusion skipped: same survivors and fusion parameters
  } reuse;
};

/// Greedy merge groups of docs/method.md 6.1 (deterministic: ties go to the lower id).
std::vector<MergeGroup> mergeGroups(const KeyframeGraph& graph, double tau_group);

/// Mean-shift with a flat kernel of radius h on count-weighted means (docs/method.md 6.2):
/// returns, for each input, the index of its cluster (0..clusters-1, in order of first member).
/// Means that all lie within h of each other form one cluster without iterating.
std::vector<int> meanShiftClusters(const std::vector<Eigen::Vector3d>& means, const std::vector<double>& weights,
                                   double h);

/// meanShiftClusters by the plain iteration of docs/method.md 6.2 from every seed, always (its reference in tests).
std::vector<int> meanShiftClustersByIteration(const std::vector<Eigen::Vector3d>& means,
                                              const std::vector<double>& weights, double h);

/// Moment matching of a cluster: n = sum n_i, mean = sum n_i mean_i / n, colour count-weighted,
/// and the covariance of the union of the clusters' points (scatters combined, see the .cpp).
Ellipsoid momentMatch(const std::vector<const Ellipsoid*>& cluster);

/// Bhattacharyya distance between the Gaussians of two ellipsoids (covariances floored at a
/// 10 um standard deviation): 1/8 d^T S^-1 d + 1/2 ln(det S / sqrt(det Sa det Sb)),
/// S = (Sa + Sb) / 2. 0 for identical ellipsoids; grows with the offset of the means relative to
/// their spread and with the difference of their shapes, so a wall patch never matches a patch
/// of the perpendicular wall at the corner.
double bhattacharyyaDistance(const Ellipsoid& a, const Ellipsoid& b);

/// Half-width (m) of the cube in which fusion looks for copies of an ellipsoid: 1.5 times the
/// median over `ellipsoids` of sqrt(lambda_max) (covariances floored as in bhattacharyyaDistance),
/// at least 10 um.
double fusionHalfWidth(const std::vector<Ellipsoid>& ellipsoids, const GlobalMapParams& params);

/// Fusion across groups (docs/method.md 7) of world-frame ellipsoids, `group_of[i]` being the merge group
/// ellipsoid i came from. Two ellipsoids are copies of one surface when they come from different
/// groups, their means lie within fusionHalfWidth() of each other along every axis, and their
/// bhattacharyyaDistance() is at most fusion_max_distance. Most precise first (smallest
/// lambda_max, then lowest index), every ellipsoid not yet fused takes from each other group its
/// nearest copy not yet fused (ties: lowest index); they become one ellipsoid by moment matching,
/// with the seed's keyframe and cell. One copy per group keeps each group's own resolution.
/// Output in the order of the seeds' indices. Deterministic for any thread count.
std::vector<Ellipsoid> fuseAcrossGroups(const std::vector<Ellipsoid>& ellipsoids, const std::vector<int>& group_of,
                                        const GlobalMapParams& params);

/// What buildGlobalMap keeps from one build to the next when it is given one: its large buffers
/// (a build writes hundreds of MB on a long session; memory first touched costs a page fault
/// and zeroing per 4 KiB, a sizeable share of a build), per keyframe the filter's kept cells while the
/// container and the filter parameters are unchanged (a loop closure moves poses only), and each
/// later stage's output with what it was computed from, so that a build re-runs only the stages
/// after what changed (GlobalMap::reuse): each merge group's merge while its members, their kept
/// cells and poses and the merge distance are unchanged; occlusion removal while the merged
/// ellipsoids, the keyframe poses, the edges and its parameters are; fusion while the survivors
/// and its parameters are. Owned by whoever rebuilds repeatedly (the workbench); it holds the
/// largest build's memory until destroyed. The map does not depend on it. One build at a time.
class GlobalMapWorkspace {
 public:
  GlobalMapWorkspace();
  ~GlobalMapWorkspace();
  GlobalMapWorkspace(const GlobalMapWorkspace&) = delete;
  GlobalMapWorkspace& operator=(const GlobalMapWorkspace&) = delete;
  /// The next build re-runs every stage (keeping the buffers and the filter's kept cells): what a
  /// build cost before the stage cache, for benchmarks.
  void forgetStages();

 private:
  friend GlobalMap buildGlobalMap(const KeyframeGraph& graph, const GlobalMapParams& params,
                                  GlobalMapWorkspace* workspace);
  struct Buffers;
  std::unique_ptr<Buffers> buffers_;
};

/// Builds the global map. Deterministic: bit for bit the same for any thread count, with or
/// without a workspace (nullptr: buffers for this build only).
/// Throws std::invalid_argument for parameters out of range; an empty graph gives an empty map.
GlobalMap buildGlobalMap(const KeyframeGraph& graph, const GlobalMapParams& params,
                         GlobalMapWorkspace* workspace = nullptr);

/// The local maps `map` was built from: every keyframe's kept ellipsoids (map.kept) in the world
/// frame, keyframes in id order (map.sigma_e of them).
std::vector<Ellipsoid> localEllipsoids(const KeyframeGraph& graph, const GlobalMap& map);

/// Calls `visit` with each of localEllipsoids(graph, map) in turn, without gathering them.
void forEachLocalEllipsoid(const KeyframeGraph& graph, const GlobalMap& map,
                           const std::function<void(const Ellipsoid&)>& visit);

/// Occlusion removal (docs/method.md 6.3) over ellipsoids in the world frame; returns, for each,
/// whether it is removed. Exposed for tests.
std::vector<bool> occludingEllipsoids(const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids,
                                      const GlobalMapParams& params);

}  // namespace vdmap
