#include "mapping/posegraph/pose_graph.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <ceres/ceres.h>

#include "mapping/core/timing.h"

namespace vdmap {
namespace {

/// Whitened SE(3) error of one edge (the definition in pose_graph.h): parameters are the
/// positions and unit quaternions (x, y, z, w as Eigen stores them) of the two nodes.
class RelativePoseCost {
 public:
  RelativePoseCost(const Transform& T_from_to, const Matrix6d& sqrt_information)
      : q_meas_inv_(Eigen::Quaterniond(T_from_to.linear()).conjugate()), p_meas_(T_from_to.translation()),
        sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* p_a_ptr, const T* q_a_ptr, const T* p_b_ptr, const T* q_b_ptr, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(p_a_ptr), p_b(p_b_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(q_a_ptr), q_b(q_b_ptr);
    const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
    const Eigen::Quaternion<T> q_meas_inv = q_meas_inv_.cast<T>();
    // E = T_meas^-1 * T_a^-1 * T_b.
    const Eigen::Matrix<T, 3, 1> p_ab = q_a_inv * (p_b - p_a);
    const Eigen::Quaternion<T> q_error = q_meas_inv * (q_a_inv * q_b);
    Eigen::Matrix<T, 6, 1> r;
    r.template head<3>() = q_meas_inv * (p_ab - p_meas_.cast<T>());
    r.template tail<3>() = T(2.0) * q_error.vec();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residual_ptr);
    residual = sqrt_information_.cast<T>() * r;
    return true;
  }

 private:
  Eigen::Quaterniond q_meas_inv_;
  Eigen::Vector3d p_meas_;
  Matrix6d sqrt_information_;
};

std::string edgeName(size_t i, const PoseGraphEdge& e) {
  return "pose graph edge " + std::to_string(i) + " (" + std::to_string(e.from) + " -> " + std::to_string(e.to) + ")";
}

/// S with S^T * S = information, or throws when the matrix is not symmetric positive definite.
Matrix6d sqrtInformation(size_t i, const PoseGraphEdge& e) {
  const Matrix6d& info = e.information;
  if (!info.allFinite()) throw std::invalid_argument(edgeName(i, e) + ": information matrix is not finite");
  if ((info - info.transpose()).cwiseAbs().maxCoeff() > 1e-9 * info.cwiseAbs().maxCoeff())
    throw std::invalid_argument(edgeName(i, e) + ": information matrix is not symmetric");
  const Eigen::LLT<Matrix6d> llt(info);
  if (llt.info() != Eigen::Success || info.cwiseAbs().maxCoeff() == 0.0)
    throw std::invalid_argument(edgeName(i, e) + ": information matrix is not positive definite");
  return llt.matrixU();
}

}  // namespace

PoseGraphResult optimizePoseGraph(std::vector<Transform>* T_W_nodes, std::span<const PoseGraphEdge> edges,
                                  const PoseGraphOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int n = static_cast<int>(T_W_nodes->size());
  for (int i = 0; i < n; ++i)
    if (!isValidTransform((*T_W_nodes)[i]))
      throw std::invalid_argument("pose graph node " + std::to_string(i) + ": pose is not a finite rigid transform");
  std::vector<Matrix6d> sqrt_information(edges.size());
  for (size_t i = 0; i < edges.size(); ++i) {
    const PoseGraphEdge& e = edges[i];
    if (e.from < 0 || e.from >= n || e.to < 0 || e.to >= n)
      throw std::invalid_argument(edgeName(i, e) + ": refers to a missing node (the graph has " + std::to_string(n) +
                                  " nodes)");
    if (e.from == e.to) throw std::invalid_argument(edgeName(i, e) + ": joins a node to itself");
    if (!isValidTransform(e.T_from_to))
      throw std::invalid_argument(edgeName(i, e) + ": relative pose is not a finite rigid transform");
    sqrt_information[i] = sqrtInformation(i, e);
  }
  for (int f : options.fixed_nodes)
    if (f < 0 || f >= n)
      throw std::invalid_argument("pose graph: fixed node " + std::to_string(f) + " does not exist (the graph has " +
                                  std::to_string(n) + " nodes)");
  if (!(options.robust_scale > 0.0) || !std::isfinite(options.robust_scale))
    throw std::invalid_argument("pose graph: robust_scale must be a positive number");
  if (options.max_iterations < 1) throw std::invalid_argument("pose graph: max_iterations must be >= 1");

  PoseGraphResult result;
  if (edges.empty()) {  // edge_chi2 stays empty, as `edges`
    result.converged = true;
    result.time_ms = msSince(start);
    return result;
  }

  std::vector<Eigen::Vector3d> p(n);
  std::vector<Eigen::Quaterniond> q(n);
  for (int i = 0; i < n; ++i) {
    p[i] = (*T_W_nodes)[i].translation();
    q[i] = Eigen::Quaterniond((*T_W_nodes)[i].linear()).normalized();
  }

  // The problem owns the cost functions, the one loss function and the one manifold it is given
  // (Ceres deletes each shared pointer once).
  ceres::Problem problem;
  ceres::LossFunction* loss = nullptr;
  if (options.robust_loss == RobustLoss::kHuber) loss = new ceres::HuberLoss(options.robust_scale);
  else loss = new ceres::CauchyLoss(options.robust_scale);
  bool loss_used = false;
  ceres::Manifold* quaternion_manifold = new ceres::EigenQuaternionManifold;
  for (size_t i = 0; i < edges.size(); ++i) {
    const PoseGraphEdge& e = edges[i];
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 3, 4, 3, 4>(
        new RelativePoseCost(e.T_from_to, sqrt_information[i]));
    problem.AddResidualBlock(cost, e.robust ? loss : nullptr, p[e.from].data(), q[e.from].coeffs().data(),
                             p[e.to].data(), q[e.to].coeffs().data());
    loss_used = loss_used || e.robust;
  }
  if (!loss_used) delete loss;
  for (int i = 0; i < n; ++i)
    if (problem.HasParameterBlock(q[i].coeffs().data())) problem.SetManifold(q[i].coeffs().data(), quaternion_manifold);
  std::vector<int> fixed = options.fixed_nodes;
  if (fixed.empty() && n > 0) fixed.push_back(0);
  std::vector<bool> moves(n, false);
  for (int i = 0; i < n; ++i) moves[i] = problem.HasParameterBlock(p[i].data());
  for (int f : fixed) {
    if (!moves[f]) continue;
    moves[f] = false;
    problem.SetParameterBlockConstant(p[f].data());
    problem.SetParameterBlockConstant(q[f].coeffs().data());
  }

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  solver.num_threads = 1;  // deterministic, and cheap enough on one thread (bench_pose_graph)
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);

  for (int i = 0; i < n; ++i) {
    if (!moves[i]) continue;  // fixed and unreached nodes keep their exact pose (no quaternion round trip)
    Transform& T = (*T_W_nodes)[i];
    T.linear() = q[i].normalized().toRotationMatrix();
    T.translation() = p[i];
  }
  result.edge_chi2.resize(edges.size());
  for (size_t i = 0; i < edges.size(); ++i) {
    const PoseGraphEdge& e = edges[i];
    Eigen::Matrix<double, 6, 1> r;
    RelativePoseCost(e.T_from_to, sqrt_information[i])(p[e.from].data(), q[e.from].coeffs().data(), p[e.to].data(),
                                                       q[e.to].coeffs().data(), r.data());
    result.edge_chi2[i] = r.squaredNorm();
  }
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.time_ms = msSince(start);
  return result;
}

}  // namespace vdmap
