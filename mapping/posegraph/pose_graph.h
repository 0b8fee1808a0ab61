#pragma once
// Pose-graph optimisation of keyframe poses with Ceres (docs/method.md 9): nodes are poses T_W_K, edges
// are measured relative poses with an information matrix. Used after a loop closure to correct
// the keyframe poses; the global map is then rebuilt from the unchanged local maps.

#include <span>
#include <vector>

#include <Eigen/Core>

#include "mapping/core/types.h"

namespace vdmap {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// A measured relative pose between two nodes: T_from_to maps points from node `to`'s frame into
/// node `from`'s frame (ideally T_W_from^-1 * T_W_to).
///
/// The residual is r = [dp; dtheta] for the error E = T_from_to^-1 * T_W_from^-1 * T_W_to:
/// dp its translation (m), dtheta twice the vector part of its unit quaternion (rad; the rotation
/// vector for small errors). `information` is the inverse covariance of r in that order
/// (translation first, then rotation); it must be symmetric positive definite. The cost of an
/// edge is 0.5 * r^T * information * r, or rho() of it when `robust`.
struct PoseGraphEdge {
  int from = 0;
  int to = 0;
  Transform T_from_to = Transform::Identity();
  Matrix6d information = Matrix6d::Identity();
  /// Apply PoseGraphOptions::robust_loss to this edge (meant for loop edges, which can be wrong).
  /// A robust edge is judged against the others' information: when the odometry edges claim less
  /// uncertainty than their real drift, a correct loop edge that contradicts the chain by many of
  /// those sigmas is down-weighted as an outlier. State the odometry's information honestly.
  bool robust = false;
};

enum class RobustLoss { kHuber, kCauchy };

struct PoseGraphOptions {
  /// Loss for edges with `robust` set. Cauchy's pull on a far outlier vanishes; Huber's stays
  /// bounded but non-zero, so a wrong loop edge still bends the graph (tests/mapping/test_pose_graph.cpp).
  RobustLoss robust_loss = RobustLoss::kCauchy;
  /// Scale of the robust loss in whitened units (sqrt of r^T * information * r): residuals below it
  /// count about fully, larger ones are down-weighted. 3.5 is about the 95% chi-square bound for
  /// 6 degrees of freedom (sqrt(12.6)), so a loop edge consistent with its information is not
  /// down-weighted.
  double robust_scale = 3.5;
  /// Nodes held constant. Empty: the first node (fixes the gauge: the graph is otherwise free to
  /// move rigidly). A part of the graph joined to no fixed node has no gauge; Levenberg-Marquardt's
  /// damping keeps it near its start.
  std::vector<int> fixed_nodes;
  int max_iterations = 100;
  /// Stop when the relative cost decrease of a step falls below this (Ceres function_tolerance).
  double function_tolerance = 1e-8;
};

struct PoseGraphResult {
  double initial_cost = 0.0;  ///< Ceres cost (0.5 * sum of squared, robustified residuals)
  double final_cost = 0.0;
  int iterations = 0;
  double time_ms = 0.0;    ///< wall time of the solve
  bool converged = false;  ///< Ceres reported convergence (not a hit iteration limit or a failure)
  /// r^T * information * r of every edge at the solution (before any robust loss), in the order
  /// of `edges`. A robust edge far above robust_scale^2 was treated as an outlier.
  std::vector<double> edge_chi2;
};

/// Optimises the node poses T_W_nodes (in place) so that they agree with the edges.
///
/// Deterministic: one thread, SPARSE_NORMAL_CHOLESKY with Eigen's sparse Cholesky, so the same
/// input gives the same output bit for bit. Throws std::invalid_argument (naming the edge or node)
/// when an edge refers to a missing node or to itself, a pose or an information matrix is not
/// finite, a rotation is not orthonormal, an information matrix is not symmetric positive
/// definite, a fixed node does not exist, or robust_scale is not positive. Nodes that no edge
/// reaches keep their pose.
PoseGraphResult optimizePoseGraph(std::vector<Transform>* T_W_nodes, std::span<const PoseGraphEdge> edges,
                                  const PoseGraphOptions& options = {});

}  // namespace vdmap
