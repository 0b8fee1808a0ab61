#pragma once
// NDT cell statistics and the merge of a batch of points into a cell (docs/method.md 2, paper
// eqs. 3-5 in Chan's parallel form). Everything here is double precision: this is the
// arithmetic the tests check to 1e-9 relative; the container stores a compact float copy.

#include <cstdint>

#include <Eigen/Core>

namespace vdmap {

/// Statistics of the points of one cell, in the frame the points were given in (the keyframe
/// frame K for local maps), metres. colour is the mean RGB in 0..255.
struct CellStats {
  double n = 0.0;  ///< number of points (double so the merge weights need no casts)
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();  ///< S = sum (p - mean)(p - mean)^T
  Eigen::Vector3d color = Eigen::Vector3d::Zero();

  /// Sigma = S / (n - 1); zero for fewer than two points (no spread is known).
  Eigen::Matrix3d covariance() const {
    return n >= 2.0 ? Eigen::Matrix3d(scatter / (n - 1.0)) : Eigen::Matrix3d::Zero();
  }
};

/// A batch of N points about to be merged into a cell: s_N = sum p, S_N = the scatter of the
/// batch about its own mean, and the sum of the colours.
struct PointBatch {
  double n = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Vector3d color_sum = Eigen::Vector3d::Zero();
};

/// Merges `batch` into `cell` exactly as docs/method.md 2 writes it:
///   delta = s_N / N - mean_M;  mean = (M mean_M + s_N) / (M + N);
///   S = S_M + S_N + delta delta^T M N / (M + N);  c = (M c_M + sum c) / (M + N);  n = M + N.
/// The mean is evaluated as mean_M + delta N / (M + N), the same quantity with less
/// cancellation. An empty batch is a no-op.
inline void mergeBatch(const PointBatch& batch, CellStats* cell) {
  const double N = batch.n, M = cell->n;
  if (N <= 0.0) return;
  const double total = M + N;
  const Eigen::Vector3d delta = batch.sum / N - cell->mean;
  cell->mean += delta * (N / total);
  cell->scatter += batch.scatter + delta * delta.transpose() * (M * N / total);
  cell->color = (M * cell->color + batch.color_sum) / total;
  cell->n = total;
}

/// The batch of a set of points (two-pass: mean first, then the scatter about it).
template <typename PointRange, typename ColorRange>
PointBatch makeBatch(const PointRange& points, const ColorRange& colors) {
  PointBatch b;
  for (const auto& p : points) {
    b.sum += p.template cast<double>();
    b.n += 1.0;
  }
  if (b.n == 0.0) return b;
  const Eigen::Vector3d mean = b.sum / b.n;
  for (const auto& p : points) {
    const Eigen::Vector3d d = p.template cast<double>() - mean;
    b.scatter += d * d.transpose();
  }
  for (const auto& c : colors) b.color_sum += c.template cast<double>();
  return b;
}

}  // namespace vdmap
