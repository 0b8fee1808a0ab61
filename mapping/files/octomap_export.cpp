#include "mapping/files/octomap_export.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <span>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <octomap/OcTree.h>

#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"
#include "mapping/query/query_map.h"

namespace vdmap {

std::vector<Eigen::Vector3d> ellipsoidSamplePoints(const Ellipsoid& e) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(e.cov);
  std::vector<Eigen::Vector3d> points = {e.mean};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d axis = std::sqrt(std::max(eig.eigenvalues()(k), 0.0)) * eig.eigenvectors().col(k);
    points.push_back(e.mean + axis);
    points.push_back(e.mean - axis);
  }
  return points;
}

double octomapExtent(const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids) {
  double extent = 0.0;
  for (const Ellipsoid& e : ellipsoids) {
    // A sample point lies within sqrt(lambda_max) <= sqrt(trace) of the mean along any axis.
    const double reach = std::sqrt(std::max(e.cov.trace(), 0.0));
    extent = std::max(extent, e.mean.cwiseAbs().maxCoeff() + reach);
    if (e.keyframe >= 0 && e.keyframe < static_cast<int>(graph.size()))
      extent = std::max(extent, graph.keyframe(e.keyframe).T_W_K.translation().cwiseAbs().maxCoeff());
  }
  return extent;
}

namespace {

// Throws std::invalid_argument for a resolution that is not > 0, or too fine for a map reaching
// `extent` m (max norm) from the origin.
void checkOctomapResolutionForExtent(double resolution_m, double extent) {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw std::invalid_argument("octomap resolution must be > 0 m");
  if (extent / resolution_m >= kOctomapMaxVoxels) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "octomap resolution %g m is too fine for this map: it reaches %.3f m from the origin and "
                  "OctoMap's 16-bit keys hold %d voxels each way, so the resolution must be at least %.3g m",
                  resolution_m, extent, kOctomapMaxVoxels, std::nextafter(extent / kOctomapMaxVoxels, INFINITY));
    throw std::invalid_argument(text);
  }
}

}  // namespace

void checkOctomapResolution(double resolution_m, const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids) {
  checkOctomapResolutionForExtent(resolution_m, octomapExtent(graph, ellipsoids));
}

OctomapExportReport writeOctomapBt(const std::filesystem::path& file, const KeyframeGraph& graph,
                                   const std::vector<Ellipsoid>& ellipsoids, double resolution_m,
                                   const ExportProgress& progress) {
  checkOctomapResolution(resolution_m, graph, ellipsoids);
  const auto start = std::chrono::steady_clock::now();
  OctomapExportReport report;
  // The ellipsoids of each keyframe, in map order (a counting sort): its scan is made when it is
  // inserted, so only one scan's points are held at a time.
  const std::size_t keyframes = graph.size();
  std::vector<std::size_t> first(keyframes + 1, 0), order(ellipsoids.size());
  for (const Ellipsoid& e : ellipsoids) {
    if (e.keyframe < 0 || static_cast<std::size_t>(e.keyframe) >= keyframes)
      throw std::logic_error("an ellipsoid of the map names no keyframe of the graph");
    ++first[static_cast<std::size_t>(e.keyframe) + 1];
  }
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<std::size_t> fill(first.begin(), first.end() - 1);
  for (std::size_t i = 0; i < ellipsoids.size(); ++i)
    order[fill[static_cast<std::size_t>(ellipsoids[i].keyframe)]++] = i;
  octomap::OcTree tree(resolution_m);
  octomap::Pointcloud scan;
  for (std::size_t k = 0; k < keyframes; ++k) {
    scan.clear();
    for (std::size_t j = first[k]; j < first[k + 1]; ++j)
      for (const Eigen::Vector3d& p : ellipsoidSamplePoints(ellipsoids[order[j]])) {
        scan.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
        ++report.points;
      }
    if (scan.size() > 0) {
      const Eigen::Vector3d o = graph.keyframe(static_cast<int>(k)).T_W_K.translation();
      // discretize: one ray per end voxel, which is what the map resolves anyway.
      tree.insertPointCloud(scan, octomap::point3d(o.x(), o.y(), o.z()), -1.0, false, true);
    }
    if (progress) progress(k + 1, keyframes);
  }
  tree.toMaxLikelihood();
  tree.prune();
  std::size_t inside = 0;
  for (const Ellipsoid& e : ellipsoids) {
    const octomap::OcTreeNode* node = tree.search(e.mean.x(), e.mean.y(), e.mean.z());
    if (node && tree.isNodeOccupied(node)) ++inside;
  }
  report.means_occupied = ellipsoids.empty() ? 1.0 : static_cast<double>(inside) / ellipsoids.size();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
    if (tree.isNodeOccupied(*it)) ++report.occupied_leaves;
  writeOctreeFile(file, tree);
  report.seconds = secondsSince(start);
  return report;
}

void writeOctreeFile(const std::filesystem::path& file, const octomap::OcTree& tree) {
  // The bytes of OcTree::writeBinaryConst, written here because liboctomap's own prints a bare
  // " done." line to stderr.
  std::ostringstream bytes;
  bytes << "# Octomap OcTree binary file\n# (feel free to add / change comments, but leave the first line as it "
           "is!)\n#\nid "
        << tree.getTreeType() << "\nsize " << tree.size() << "\nres " << tree.getResolution() << "\ndata\n";
  if (tree.getRoot()) tree.writeBinaryNode(bytes, tree.getRoot());
  writeFileAtomically(file, bytes.str());
}

QueryOctomapReport writeOctomapBtFromQuery(const std::filesystem::path& file, const QueryMap& map, double resolution_m,
                                           const ExportProgress& progress) {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw std::invalid_argument("octomap resolution must be > 0 m");
  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  if (!(lo.array() <= hi.array()).all())
    throw std::invalid_argument(
        "the map sees nothing (no keyframe with a kept cell): there is no region to fill an OctoMap with");
  checkOctomapResolutionForExtent(resolution_m, std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()));
  const auto start = std::chrono::steady_clock::now();
  octomap::OcTree tree(resolution_m);
  octomap::OcTreeKey k_lo, k_hi;
  for (int a = 0; a < 3; ++a) {
    k_lo[a] = tree.coordToKey(lo[a]);
    k_hi[a] = tree.coordToKey(hi[a]);
  }
  const std::size_t nx = k_hi[0] - k_lo[0] + 1u, ny = k_hi[1] - k_lo[1] + 1u, nz = k_hi[2] - k_lo[2] + 1u;
  if (static_cast<double>(nx) * ny * nz > static_cast<double>(kMaxQueryOctomapVoxels)) {
    char text[256];
    std::snprintf(
        text, sizeof text,
        "octomap resolution %g m over the seen %.3g x %.3g x %.3g m would ask about %.3g voxels (at most %zu): "
        "give a coarser resolution",
        resolution_m, hi.x() - lo.x(), hi.y() - lo.y(), hi.z() - lo.z(), static_cast<double>(nx) * ny * nz,
        kMaxQueryOctomapVoxels);
    throw std::invalid_argument(text);
  }
  const double half_diagonal = resolution_m * std::sqrt(3.0) / 2;
  const float occupied_value = tree.getClampingThresMaxLog(), free_value = tree.getClampingThresMinLog();
  QueryOctomapReport report;
  std::vector<Eigen::Vector3d> centres(nx * ny), open;
  std::vector<DistanceResult> distances(centres.size());
  std::vector<Classification> classes;
  std::vector<octomap::OcTreeKey> open_keys;
  for (std::size_t z = 0; z < nz; ++z) {
    // One layer of voxels at a time: their centres, then occupied, then free among the others.
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(k_lo[0] + x),
                                     static_cast<octomap::key_type>(k_lo[1] + y),
                                     static_cast<octomap::key_type>(k_lo[2] + z));
        const octomap::point3d c = tree.keyToCoord(key);
        centres[y * nx + x] = {c.x(), c.y(), c.z()};
      }
    map.distance(centres, distances, 2 * half_diagonal);
    report.voxels += centres.size();
    open.clear();
    open_keys.clear();
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(k_lo[0] + x),
                                     static_cast<octomap::key_type>(k_lo[1] + y),
                                     static_cast<octomap::key_type>(k_lo[2] + z));
        if (distances[y * nx + x].distance_m <= half_diagonal) {
          tree.setNodeValue(key, occupied_value, true);
          ++report.occupied_voxels;
        } else {
          open.push_back(centres[y * nx + x]);
          open_keys.push_back(key);
        }
      }
    classes.resize(open.size());
    map.classify(open, classes);
    for (std::size_t i = 0; i < open.size(); ++i)
      if (classes[i].state == Occupancy::kFree) {
        tree.setNodeValue(open_keys[i], free_value, true);
        ++report.free_voxels;
      }
    if ((z + 1) % 16 == 0) tree.prune();  // keeps the tree small while it fills
    if (progress) progress(z + 1, nz);
  }
  tree.updateInnerOccupancy();
  tree.prune();
  report.leaves = tree.getNumLeafNodes();
  writeOctreeFile(file, tree);
  report.seconds = secondsSince(start);
  return report;
}

}  // namespace vdmap
