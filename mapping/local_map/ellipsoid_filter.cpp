#include "mapping/local_map/ellipsoid_filter.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace vdmap {
namespace {

double largestEigenvalue(const Eigen::Matrix3d& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(m, Eigen::EigenvaluesOnly);
  return solver.eigenvalues()(2);  // ascending
}

// keepCell on the cell's statistics; *cov receives their covariance once the point count passes.
bool keepStats(const CellStats& stats, const KeyframeContainer& container, const FilterParams& filter,
               Eigen::Matrix3d* cov) {
  // Fewer than two points have no covariance at all; treat them as rejected whatever
  // min_points says.
  if (stats.n < std::max(filter.min_points, 2)) return false;
  if (!(stats.mean.z() > 0.0)) return false;
  *cov = stats.covariance();
  const Eigen::Vector2d uv = container.camera().project(stats.mean);
  const Eigen::Matrix3d expected = expectedCellCovariance(
      filter.model, container.camera(), uv.x(), uv.y(), stats.mean.z(), container.cellSizePx());
  // Compare variances: sqrt(a) <= k sqrt(b)  <=>  a <= k^2 b for a, b >= 0.
  const double k = filter.filter_sigma_factor;
  return largestEigenvalue(*cov) <= k * k * largestEigenvalue(expected);
}

}  // namespace

bool keepCell(const StoredCell& cell, const KeyframeContainer& container, const FilterParams& filter) {
  Eigen::Matrix3d cov;
  return keepStats(cell.toStats(), container, filter, &cov);
}

void forEachKeptEllipsoid(const KeyframeContainer& container, const FilterParams& filter,
                          const Transform& T_X_K, int keyframe_id,
                          const std::function<void(const Ellipsoid&)>& visit) {
  const Eigen::Matrix3d R = T_X_K.linear();
  for (const StoredCell& cell : container.cells()) {
    const CellStats stats = cell.toStats();
    Eigen::Matrix3d cov;
    if (!keepStats(stats, container, filter, &cov)) continue;
    Ellipsoid e;
    e.mean = T_X_K * stats.mean;
    e.cov = R * cov * R.transpose();
    e.color = cell.color;
    e.count = cell.n;
    e.keyframe = keyframe_id;
    e.grid_index = cell.grid_index;
    visit(e);
  }
}

std::vector<Ellipsoid> keptEllipsoids(const KeyframeContainer& container, const FilterParams& filter,
                                      const Transform& T_X_K, int keyframe_id) {
  std::vector<Ellipsoid> out;
  forEachKeptEllipsoid(container, filter, T_X_K, keyframe_id,
                       [&out](const Ellipsoid& e) { out.push_back(e); });
  return out;
}

}  // namespace vdmap
