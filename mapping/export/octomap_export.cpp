#include "mapping/export/octomap_export.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <octomap/OcTree.h>

#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"

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

void checkOctomapResolution(double resolution_m, const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids) {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw std::invalid_argument("octomap resolution must be > 0 m");
  const double extent = octomapExtent(graph, ellipsoids);
  if (extent / resolution_m >= kOctomapMaxVoxels) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "octomap resolution %g m is too fine for this map: it reaches %.3f m from the origin and "
                  "OctoMap's 16-bit keys hold %d voxels each way, so the resolution must be at least %.3g m",
                  resolution_m, extent, kOctomapMaxVoxels, std::nextafter(extent / kOctomapMaxVoxels, INFINITY));
    throw std::invalid_argument(text);
  }
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
  for (std::size_t i = 0; i < ellipsoids.size(); ++i) order[fill[static_cast<std::size_t>(ellipsoids[i].keyframe)]++] = i;
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
  // The bytes of OcTree::writeBinaryConst, written here because liboctomap's own prints a bare
  // " done." line to stderr.
  std::ostringstream bytes;
  bytes << "# Octomap OcTree binary file\n# (feel free to add / change comments, but leave the first line as it "
           "is!)\n#\nid "
        << tree.getTreeType() << "\nsize " << tree.size() << "\nres " << tree.getResolution() << "\ndata\n";
  if (tree.getRoot()) tree.writeBinaryNode(bytes, tree.getRoot());
  writeFileAtomically(file, bytes.str());
  report.seconds = secondsSince(start);
  return report;
}

}  // namespace vdmap
