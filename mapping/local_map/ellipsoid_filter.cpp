#include "mapping/local_map/ellipsoid_filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace vdmap {
double largestEigenvalue(const Eigen::Matrix3d& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(m, Eigen::EigenvaluesOnly);
  return solver.eigenvalues()(2);  // ascending
}

namespace {

// Bounds on the largest eigenvalue of a symmetric matrix without its trigonometry (the filter runs
// on every cell of every keyframe at each global-map rebuild): it is at least the largest diagonal
// entry (a Rayleigh quotient) and at most the Frobenius norm (sqrt of the sum of squared eigenvalues).
double largestEigenvalueAtLeast(const Eigen::Matrix3d& m) { return m.diagonal().maxCoeff(); }
double largestEigenvalueAtMost(const Eigen::Matrix3d& m) { return m.norm(); }

}  // namespace

bool keepCell(const StoredCell& cell, const KeyframeContainer& container, const FilterParams& filter) {
  // Fewer than two points have no covariance at all; treat them as rejected whatever
  // min_points says.
  const CellStats stats = cell.toStats();
  if (stats.n < std::max(filter.min_points, 2)) return false;
  if (!(stats.mean.z() > 0.0)) return false;
  const Eigen::Vector2d uv = container.camera().project(stats.mean);
  const Eigen::Matrix3d expected =
      expectedCellCovariance(filter.model, container.camera(), uv.x(), uv.y(), stats.mean.z(), container.cellSizePx());
  // Compare variances: sqrt(a) <= k sqrt(b)  <=>  a <= k^2 b for a, b >= 0.
  const double k2 = filter.filter_sigma_factor * filter.filter_sigma_factor;
  const Eigen::Matrix3d cov = stats.covariance();
  // Most cells are far from the threshold, and the bounds decide them as the eigenvalues would;
  // the margin covers the eigen solver's rounding (relative 1e-15) many times over.
  constexpr double kMargin = 1e-6;
  if (largestEigenvalueAtMost(cov) * (1.0 + kMargin) < k2 * largestEigenvalueAtLeast(expected) * (1.0 - kMargin))
    return true;
  if (largestEigenvalueAtLeast(cov) * (1.0 - kMargin) > k2 * largestEigenvalueAtMost(expected) * (1.0 + kMargin))
    return false;
  return largestEigenvalue(cov) <= k2 * largestEigenvalue(expected);
}

std::vector<bool> keptCells(const KeyframeContainer& container, const FilterParams& filter) {
  std::vector<bool> kept;
  kept.reserve(container.size());
  for (const StoredCell& cell : container.cells()) kept.push_back(keepCell(cell, container, filter));
  return kept;
}

void forEachKeptEllipsoid(const KeyframeContainer& container, const std::vector<bool>& kept, const Transform& T_X_K,
                          int keyframe_id, const std::function<void(const Ellipsoid&)>& visit) {
  if (kept.size() != container.size())
    throw std::invalid_argument("forEachKeptEllipsoid: kept does not fit the container");
  for (std::size_t i = 0; i < kept.size(); ++i)
    if (kept[i]) visit(cellEllipsoid(container.cells()[i], T_X_K, keyframe_id));
}

Ellipsoid cellEllipsoid(const StoredCell& cell, const Transform& T_X_K, int keyframe_id) {
  const Eigen::Matrix3d R = T_X_K.linear();
  const CellStats stats = cell.toStats();
  Ellipsoid e;
  e.mean = T_X_K * stats.mean;
  e.cov = R * stats.covariance() * R.transpose();
  e.color = cell.color;
  e.count = cell.n;
  e.keyframe = keyframe_id;
  e.grid_index = cell.grid_index;
  return e;
}

std::vector<Ellipsoid> keptEllipsoids(const KeyframeContainer& container, const FilterParams& filter,
                                      const Transform& T_X_K, int keyframe_id) {
  std::vector<Ellipsoid> out;
  forEachKeptEllipsoid(container, keptCells(container, filter), T_X_K, keyframe_id,
                       [&out](const Ellipsoid& e) { out.push_back(e); });
  return out;
}

}  // namespace vdmap
