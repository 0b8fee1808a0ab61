#include "mapping/tracking/map_registration.h"

#include <chrono>

#include <Eigen/SparseCholesky>

#include "mapping/core/parallel.h"
#include "mapping/core/timing.h"

namespace vdmap {

namespace {

// B's ellipsoid means (B's frame), what registerLocalMaps aligns. Tried instead: B's map rendered
// at B's pixels (each pixel's ray cut with its cell's plane, no grid to line up) with B's
// keypoints as feature terms (estimateRelativePose), and the means with feature terms: neither
// did better on both Replica and 7-Scenes (docs/notes/tracking.md has the figures).
DensePoints cellMeans(const KeyframeContainer& map, int min_points) {
  DensePoints points;
  for (const StoredCell& c : map.cells())
    if (c.n >= static_cast<std::uint32_t>(min_points)) points.points_C.push_back(c.mean);
  return points;
}

std::optional<PoseGraphEdge> registerMeans(const Keyframe& A, const Keyframe& B, const DensePoints& points,
                                           const MapRefinementParams& params) {
  const Transform start = A.T_W_K.inverse() * B.T_W_K;
  RelativePose estimate;
  estimate.T_K_C = start;
  estimate.dense = refineAgainstLocalMap(A.container, points, {}, &estimate.T_K_C, params.relative.dense);
  if (estimate.dense.inliers < params.relative.min_dense_inliers ||
      estimate.dense.inlierRatio() < params.relative.min_dense_inlier_ratio ||
      translationBetween(start, estimate.T_K_C) > params.relative.max_jump_m ||
      degreesBetween(start, estimate.T_K_C) > params.relative.max_jump_deg ||
      estimate.dense.translationConditioning() < params.min_conditioning)
    return std::nullopt;
  estimate.status = RelativePose::Status::kGood;
  estimate.dense_trusted = true;
  return PoseGraphEdge{A.id, B.id, estimate.T_K_C, edgeInformation(estimate, params.edge_noise), false};
}

// A pose-graph edge's residual at the poses T_W (pose_graph.h: the translation and the rotation
// of E = T_from_to^-1 T_W_from^-1 T_W_to, translation first).
Eigen::Matrix<double, 6, 1> edgeResidual(const PoseGraphEdge& e, const std::vector<Transform>& T_W) {
  const Transform E =
      e.T_from_to.inverse() * T_W[static_cast<std::size_t>(e.from)].inverse() * T_W[static_cast<std::size_t>(e.to)];
  Eigen::Quaterniond q(E.linear());
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  Eigen::Matrix<double, 6, 1> r;
  r << E.translation(), 2.0 * q.vec();
  return r;
}

// The joint refinement's objective at given poses and Tukey threshold.
struct JointCost {
  std::vector<NdtRefinementResult> pairs;  ///< each pair's linearisation, in the order of the pairs
  /// The pairs' Tukey losses, sum of k^2/6 (1 - (1 - u)^3) = k^2/6 (points - support), whose
  /// Gauss-Newton model the pairs' normal equations are, plus the edges' 0.5 r^T information r
  /// (the constant k^2/6 points left out).
  double value = 0;
};

// What the joint cost is made of, all unchanged while the poses move: the covisible pairs, each
// pair's points (B's means that were inliers of A's map at the starting poses) and each
// keyframe's cell distributions (A's side; empty for a keyframe that is no pair's A).
struct JointTerms {
  const std::vector<CovisibilityEdge>& pairs;
  std::vector<DensePoints> points;
  std::vector<std::vector<CellDistribution>> cells;
};

JointCost jointCost(const KeyframeGraph& graph, const JointTerms& terms, std::span<const PoseGraphEdge> edges,
                    const std::vector<Transform>& T_W, const NdtRefinementParams& cost, int threads) {
  const std::vector<CovisibilityEdge>& pairs = terms.pairs;
  JointCost out;
  out.pairs.resize(pairs.size());
  parallelFor(threads, pairs.size(), [&](std::size_t i) {
    const auto a = static_cast<std::size_t>(pairs[i].a), b = static_cast<std::size_t>(pairs[i].b);
    out.pairs[i] = lineariseAgainstLocalMap(graph.keyframe(pairs[i].a).container, terms.cells[a], terms.points[i],
                                            T_W[a].inverse() * T_W[b], cost);
  });
  double support = 0;
  for (const NdtRefinementResult& p : out.pairs) support += p.support;  // in order: the same sum whatever the threads
  out.value = -cost.robust_k * cost.robust_k / 6.0 * support;
  for (const PoseGraphEdge& e : edges) {
    const Eigen::Matrix<double, 6, 1> r = edgeResidual(e, T_W);
    out.value += 0.5 * r.dot(e.information * r);
  }
  return out;
}

// 64-bit indices, not Eigen's default int: libceres.a instantiates the same sparse templates for
// int, and the linker keeps one copy of each for both. In the AddressSanitizer build, where Eigen
// aligns its allocations by hand (it does not trust ASan's malloc) and uninstrumented Ceres does
// not, Ceres's Cholesky then freed a matrix our copy had allocated (a bad free in loop closure).
using SparseIndex = std::int64_t;

// The Levenberg-Marquardt step of every keyframe but 0 (rows 6 (k - 1)) from the linearisation
// at T_W, damped by lambda; empty when the normal equations cannot be solved. Poses are perturbed
// on the right, T_W_K exp(d_K): a pair's step xi (T_A_B <- exp(xi) T_A_B) is then -d_A +
// Ad(T_A_B) d_B, so its normal matrix H and gradient g enter the blocks (A, A) H, (A, B) -H Ad,
// (B, B) Ad^T H Ad and the gradients -g, Ad^T g; an edge's residual moves by
// -Ad(T_from_to^-1) d_from + d_to (E near the identity).
Eigen::VectorXd jointStep(const std::vector<CovisibilityEdge>& pairs, const JointCost& cost,
                          std::span<const PoseGraphEdge> edges, const std::vector<Transform>& T_W, double lambda) {
  const int dim = 6 * (static_cast<int>(T_W.size()) - 1);
  std::vector<Eigen::Triplet<double, SparseIndex>> H;  // summed by setFromTriplets
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(dim), g = Eigen::VectorXd::Zero(dim);
  const auto add = [&H, &diagonal](int row_kf, int col_kf, const Matrix6d& block) {
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) H.emplace_back(6 * (row_kf - 1) + r, 6 * (col_kf - 1) + c, block(r, c));
    if (row_kf == col_kf) diagonal.segment<6>(6 * (row_kf - 1)) += block.diagonal();
  };
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const int a = pairs[i].a, b = pairs[i].b;
    const Matrix6d Ad = adjoint(T_W[static_cast<std::size_t>(a)].inverse() * T_W[static_cast<std::size_t>(b)]);
    const Matrix6d& Hp = cost.pairs[i].information;
    const Matrix6d HAd = Hp * Ad;
    if (a > 0) add(a, a, Hp), g.segment<6>(6 * (a - 1)) -= cost.pairs[i].gradient;
    if (b > 0) add(b, b, Ad.transpose() * HAd), g.segment<6>(6 * (b - 1)) += Ad.transpose() * cost.pairs[i].gradient;
    if (a > 0 && b > 0) add(a, b, -HAd), add(b, a, -HAd.transpose());
  }
  for (const PoseGraphEdge& e : edges) {
    const Eigen::Matrix<double, 6, 1> r = edgeResidual(e, T_W);
    const Matrix6d J_from = -adjoint(e.T_from_to.inverse());
    const Matrix6d JtL = J_from.transpose() * e.information;
    if (e.from > 0) add(e.from, e.from, JtL * J_from), g.segment<6>(6 * (e.from - 1)) += JtL * r;
    if (e.to > 0) add(e.to, e.to, e.information), g.segment<6>(6 * (e.to - 1)) += e.information * r;
    if (e.from > 0 && e.to > 0) add(e.from, e.to, JtL), add(e.to, e.from, JtL.transpose());
  }
  // Marquardt's damping, with a floor so a keyframe nothing constrains stays put.
  const double floor = 1e-9 * std::max(diagonal.maxCoeff(), 1e-12);
  for (int j = 0; j < dim; ++j) H.emplace_back(j, j, lambda * std::max(diagonal(j), floor));
  Eigen::SparseMatrix<double, Eigen::ColMajor, SparseIndex> normal(dim, dim);
  normal.setFromTriplets(H.begin(), H.end());
  const Eigen::SimplicialLDLT<decltype(normal)> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return {};
  Eigen::VectorXd d = -ldlt.solve(g);
  return d.allFinite() ? d : Eigen::VectorXd();
}

// MapRefinementMethod::kJoint (keyframe 0 fixed). The pose graph's measured edges (not the robust
// loop edges) stay in the cost as they are, so what the maps leave free (a corridor's length, two
// walls' line) keeps tracking's estimate. Each pair's points are the means of B that are inliers
// of A's map at the starting poses, fixed for the whole refinement: with every mean counted, a
// pose that brings more of them onto the map lowers the Tukey cost, and where the maps pin little
// (a box room's walls) the keyframes slid towards more overlap and away from the truth, which the
// fixed set stops (docs/notes/tracking.md).
void refineJointly(KeyframeGraph* graph, KeyframePoseGraph* pose_graph, const std::vector<CovisibilityEdge>& pairs,
                   const std::vector<DensePoints>& means, const MapRefinementParams& params,
                   MapRefinementResult* result) {
  const int n = static_cast<int>(graph->size());
  if (n < 2) return;
  std::vector<Transform> T_W;
  for (const Keyframe& k : graph->keyframes()) T_W.push_back(k.T_W_K);
  JointTerms terms{pairs, std::vector<DensePoints>(pairs.size()),
                   std::vector<std::vector<CellDistribution>>(graph->size())};
  std::vector<char> is_a(graph->size(), 0);
  for (const CovisibilityEdge& e : pairs) is_a[static_cast<std::size_t>(e.a)] = 1;
  parallelFor(params.threads, terms.cells.size(), [&](std::size_t k) {
    if (is_a[k]) terms.cells[k] = cellDistributions(graph->keyframe(static_cast<int>(k)).container, params.joint);
  });
  parallelFor(params.threads, pairs.size(), [&](std::size_t i) {
    const auto a = static_cast<std::size_t>(pairs[i].a), b = static_cast<std::size_t>(pairs[i].b);
    std::vector<std::uint8_t> inlier;
    lineariseAgainstLocalMap(graph->keyframe(pairs[i].a).container, terms.cells[a], means[b], T_W[a].inverse() * T_W[b],
                             params.joint, &inlier);
    for (std::size_t j = 0; j < inlier.size(); ++j)
      if (inlier[j]) terms.points[i].points_C.push_back(means[b].points_C[j]);
  });
  std::vector<PoseGraphEdge> measured;
  for (const PoseGraphEdge& e : pose_graph->edges())
    if (!e.robust) measured.push_back(e);
  JointCost cost = jointCost(*graph, terms, measured, T_W, params.joint, params.threads);
  double lambda = 1e-4;
  for (int it = 0; it < params.joint_iterations && lambda <= 1e6; ++it) {
    const Eigen::VectorXd d = jointStep(pairs, cost, measured, T_W, lambda);
    if (d.size() == 0) {
      lambda *= 10;
      continue;
    }
    std::vector<Transform> trial = T_W;
    double largest_m = 0;
    for (int k = 1; k < n; ++k) {
      const Eigen::Matrix<double, 6, 1> step = d.segment<6>(6 * (k - 1));
      Transform& T = trial[static_cast<std::size_t>(k)];
      T = T * stepTransform(step);
      T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();  // exactly a rotation
      largest_m = std::max(largest_m, step.head<3>().norm());
    }
    JointCost trial_cost = jointCost(*graph, terms, measured, trial, params.joint, params.threads);
    if (trial_cost.value >= cost.value) {
      lambda *= 4;
      continue;
    }
    T_W = std::move(trial);
    cost = std::move(trial_cost);
    lambda = std::max(lambda / 3, 1e-7);
    ++result->rounds;
    if (largest_m < params.joint_converged_m) break;
  }
  // Started from tracked poses, a pair's relative pose changes by millimetres, well within
  // max_jump; where the starting poses were too far off for the inlier sets, the refinement can
  // run off (a lone pair ended far away): then nothing is kept (docs/notes/tracking.md).
  for (const CovisibilityEdge& e : pairs) {
    const Transform before = graph->keyframe(e.a).T_W_K.inverse() * graph->keyframe(e.b).T_W_K;
    const Transform after = T_W[static_cast<std::size_t>(e.a)].inverse() * T_W[static_cast<std::size_t>(e.b)];
    if (translationBetween(before, after) > params.relative.max_jump_m ||
        degreesBetween(before, after) > params.relative.max_jump_deg) {
      result->refused = true;
      return;
    }
  }
  pose_graph->keepPosesBefore(*graph);
  for (int k = 1; k < n; ++k) graph->setKeyframePose(k, T_W[static_cast<std::size_t>(k)]);
  // The pose graph keeps what the refinement found: each trusted pair's relative pose as its edge.
  std::vector<PoseGraphEdge> edges;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (cost.pairs[i].inliers < params.relative.min_dense_inliers) continue;
    RelativePose estimate;
    estimate.T_K_C = T_W[static_cast<std::size_t>(pairs[i].a)].inverse() * T_W[static_cast<std::size_t>(pairs[i].b)];
    estimate.dense = cost.pairs[i];
    estimate.status = RelativePose::Status::kGood;
    estimate.dense_trusted = true;
    edges.push_back({pairs[i].a, pairs[i].b, estimate.T_K_C, edgeInformation(estimate, params.edge_noise), false});
  }
  result->edges = static_cast<int>(edges.size());
  pose_graph->replaceMeasuredEdges(edges);
}

}  // namespace

std::optional<PoseGraphEdge> registerLocalMaps(const Keyframe& A, const Keyframe& B,
                                               const MapRefinementParams& params) {
  return registerMeans(A, B, cellMeans(B.container, params.min_cell_points), params);
}

MapRefinementResult refineKeyframePoses(KeyframeGraph* graph, KeyframePoseGraph* pose_graph,
                                        const PoseGraphOptions& options, const MapRefinementParams& params) {
  const auto start = std::chrono::steady_clock::now();
  MapRefinementResult result;
  const std::vector<CovisibilityEdge> pairs = graph->edges().edges();
  result.pairs = static_cast<int>(pairs.size());
  std::vector<Transform> initial;
  for (const Keyframe& k : graph->keyframes()) initial.push_back(k.T_W_K);
  // The local maps do not change, only the poses: each keyframe's means once for every round.
  std::vector<DensePoints> means(graph->size());
  if (!pairs.empty())
    parallelFor(params.threads, means.size(), [&](std::size_t k) {
      means[k] = cellMeans(graph->keyframe(static_cast<int>(k)).container, params.min_cell_points);
    });
  if (params.method == MapRefinementMethod::kJoint && !pairs.empty())
    refineJointly(graph, pose_graph, pairs, means, params, &result);
  for (int round = 0; params.method == MapRefinementMethod::kPairwise && round < params.max_rounds && !pairs.empty();
       ++round) {
    std::vector<std::optional<PoseGraphEdge>> measured(pairs.size());
    parallelFor(params.threads, pairs.size(), [&](std::size_t i) {
      const CovisibilityEdge& e = pairs[i];
      measured[i] =
          registerMeans(graph->keyframe(e.a), graph->keyframe(e.b), means[static_cast<std::size_t>(e.b)], params);
    });
    std::vector<PoseGraphEdge> edges;
    for (const auto& e : measured)
      if (e) edges.push_back(*e);
    result.edges = static_cast<int>(edges.size());
    if (edges.empty()) break;
    pose_graph->replaceMeasuredEdges(edges);
    ++result.rounds;
    if (pose_graph->optimise(graph, options, nullptr, round > 0) < params.converged_m) break;
  }
  for (std::size_t i = 0; i < initial.size(); ++i)
    result.moved_m = std::max(
        result.moved_m, (graph->keyframe(static_cast<int>(i)).T_W_K.translation() - initial[i].translation()).norm());
  result.ms = msSince(start);
  return result;
}

}  // namespace vdmap
