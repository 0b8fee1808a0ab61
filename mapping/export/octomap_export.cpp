#include "mapping/export/octomap_export.h"

#include <chrono>
#include <cmath>
#include <cstdio>
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
  std::vector<octomap::Pointcloud> scans(graph.size());
  for (const Ellipsoid& e : ellipsoids)
    for (const Eigen::Vector3d& p : ellipsoidSamplePoints(e)) {
      scans.at(static_cast<std::size_t>(e.keyframe)).push_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                                              static_cast<float>(p.z()));
      ++report.points;
    }
  octomap::OcTree tree(resolution_m);
  for (std::size_t k = 0; k < scans.size(); ++k) {
    if (scans[k].size() > 0) {
      const Eigen::Vector3d o = graph.keyframe(static_cast<int>(k)).T_W_K.translation();
      // discretize: one ray per end voxel, which is what the map resolves anyway.
      tree.insertPointCloud(scans[k], octomap::point3d(o.x(), o.y(), o.z()), -1.0, false, true);
    }
    if (progress) progress(k + 1, scans.size());
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
