#pragma once
// OctoMap export of the global map (docs/method.md 11), through liboctomap.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <vector>

#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/local_map/ellipsoid_filter.h"

namespace octomap {
class OcTree;
}

namespace vdmap {

class QueryMap;

/// Called with (done, total) steps of a long export, from the exporting thread.
using ExportProgress = std::function<void(std::size_t done, std::size_t total)>;

/// What writeOctomapBt built.
struct OctomapExportReport {
  std::size_t points = 0;           ///< points sampled from the ellipsoids and inserted
  std::size_t occupied_leaves = 0;  ///< occupied leaves of the pruned tree
  double means_occupied = 0;        ///< fraction of the ellipsoid means in an occupied voxel
  double seconds = 0;               ///< wall time of building and serialising
};

/// The points an ellipsoid contributes to the OctoMap: its mean and the mean +- one standard
/// deviation along each principal axis (7 points; the sigma points of the Gaussian), world frame.
std::vector<Eigen::Vector3d> ellipsoidSamplePoints(const Ellipsoid& e);

/// OctoMap addresses voxels with 16-bit keys centred on the origin: a coordinate must satisfy
/// |c| / resolution < 32768 (liboctomap's tree_max_val); one voxel is kept as margin.
inline constexpr int kOctomapMaxVoxels = 32767;

/// How far (m, max norm) the OctoMap of `ellipsoids` reaches from the origin: the sample points
/// (bounded by mean +- sqrt(trace Sigma)) and the sensor origins of their keyframes.
double octomapExtent(const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids);

/// Throws std::invalid_argument for a resolution that is not > 0 and finite, or one so fine that
/// the map's extent does not fit in OctoMap's keys (liboctomap would drop those points with a
/// warning each and write a wrong map); the message names the finest resolution that fits.
void checkOctomapResolution(double resolution_m, const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids);

/// Builds an OctoMap (octomap::OcTree, default sensor model) of `resolution_m` from world-frame
/// `ellipsoids`: their sample points are inserted as one scan per keyframe (Ellipsoid::keyframe)
/// with that keyframe's centre as the sensor origin, so free space is carved along the rays
/// (docs/method.md 11). Writes the binary .bt atomically. Throws std::invalid_argument for a
/// resolution checkOctomapResolution refuses, std::runtime_error naming `file` when it cannot
/// be written.
/// `progress`, when given, is called after each keyframe's scan with (done, total) scans.
OctomapExportReport writeOctomapBt(const std::filesystem::path& file, const KeyframeGraph& graph,
                                   const std::vector<Ellipsoid>& ellipsoids, double resolution_m,
                                   const ExportProgress& progress = {});

/// Writes `tree` as a binary .bt (the bytes of OcTree::writeBinaryConst, written here because
/// liboctomap's own prints a bare " done." line to stderr) atomically. Throws std::runtime_error
/// naming `file` when it cannot be written.
void writeOctreeFile(const std::filesystem::path& file, const octomap::OcTree& tree);

/// What writeOctomapBtFromQuery built.
struct QueryOctomapReport {
  std::size_t voxels = 0;           ///< voxel centres of the seen region asked about
  std::size_t occupied_voxels = 0;  ///< before pruning
  std::size_t free_voxels = 0;
  std::size_t leaves = 0;  ///< leaves of the pruned tree
  double seconds = 0;
};

/// Most voxels writeOctomapBtFromQuery asks about (a resolution far too fine is refused).
inline constexpr std::size_t kMaxQueryOctomapVoxels = std::size_t{1} << 31;

/// An OctoMap whose free space is the view-dependent free space (docs/method.md 13) instead of
/// rays carved from sample points: every voxel of `resolution_m` whose centre lies in
/// QueryMap::seenBounds is occupied when the centre is within the voxel's half-diagonal
/// (res sqrt(3) / 2) of a surface (QueryMap::distance), else free when the centre is classified
/// free, else left out (unknown). Occupied and free voxels hold the tree's clamping log-odds (what
/// toMaxLikelihood gives); the tree is pruned and written as writeOctreeFile does. Throws
/// std::invalid_argument for a resolution that is not > 0, one too fine for OctoMap's keys or for
/// kMaxQueryOctomapVoxels, or an empty map (nothing seen). `progress`: (layers done, layers).
QueryOctomapReport writeOctomapBtFromQuery(const std::filesystem::path& file, const QueryMap& map, double resolution_m,
                                           const ExportProgress& progress = {});

}  // namespace vdmap
