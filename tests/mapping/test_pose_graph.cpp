// Pose-graph optimisation (mapping/posegraph): conventions on two-node graphs with an exact
// answer, a noisy 100-pose loop pulled back by one loop edge, a wrong loop edge down-weighted by
// the robust loss, the gauge, and refused input.
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/posegraph/pose_graph.h"

namespace vdmap {
namespace {

constexpr double kDeg = M_PI / 180.0;

Transform pose(double x, double y, double z, double yaw, double pitch = 0.0, double roll = 0.0) {
  Transform T = Transform::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

double angleBetween(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

Matrix6d information(double sigma_m, double sigma_rad) {
  Matrix6d info = Matrix6d::Zero();
  info.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return info;
}

double maxPositionError(const std::vector<Transform>& a, const std::vector<Transform>& b) {
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i].translation() - b[i].translation()).norm());
  return worst;
}

double maxAngleError(const std::vector<Transform>& a, const std::vector<Transform>& b) {
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, angleBetween(a[i], b[i]));
  return worst;
}

// The edge's convention (pose_graph.h): node `to` ends at T_W_from * T_from_to.
TEST(PoseGraph, TwoNodesEndAtTheMeasuredRelativePose) {
  const Transform T_W_0 = pose(1.0, -0.5, 2.0, 30 * kDeg, 10 * kDeg, -5 * kDeg);
  const Transform T_0_1 = pose(0.3, 0.1, -0.2, -20 * kDeg, 5 * kDeg, 15 * kDeg);
  std::vector<Transform> nodes = {T_W_0, pose(0, 0, 0, 0)};
  const std::vector<PoseGraphEdge> edges = {{0, 1, T_0_1, information(0.01, 0.01), false}};
  const PoseGraphResult result = optimizePoseGraph(&nodes, edges);
  EXPECT_TRUE(result.converged);
  EXPECT_GT(result.initial_cost, 1.0);
  EXPECT_LT(result.final_cost, 1e-12);
  EXPECT_TRUE(nodes[0].isApprox(T_W_0, 0.0)) << "the first node fixes the gauge";
  const Transform expected = T_W_0 * T_0_1;
  EXPECT_LT((nodes[1].translation() - expected.translation()).norm(), 1e-7);
  EXPECT_LT(angleBetween(nodes[1], expected), 1e-7);
}

// Information is ordered translation first, then rotation: of two edges that disagree, one sure of
// its translation and one sure of its rotation, each wins its own part.
TEST(PoseGraph, InformationOrderIsTranslationThenRotation) {
  const Transform a = pose(1.0, 0.0, 0.0, 0.0);
  const Transform b = pose(0.0, 1.0, 0.0, 40 * kDeg);
  std::vector<Transform> nodes = {Transform::Identity(), Transform::Identity()};
  Matrix6d sure_of_translation = Matrix6d::Identity(), sure_of_rotation = Matrix6d::Identity();
  sure_of_translation.topLeftCorner<3, 3>() *= 1e8;
  sure_of_rotation.bottomRightCorner<3, 3>() *= 1e8;
  const std::vector<PoseGraphEdge> edges = {{0, 1, a, sure_of_translation, false}, {0, 1, b, sure_of_rotation, false}};
  optimizePoseGraph(&nodes, edges);
  EXPECT_LT((nodes[1].translation() - a.translation()).norm(), 1e-4);
  EXPECT_LT(angleBetween(nodes[1], b), 1e-4);
}

/// A loop of n poses on a 2 m circle, with some height and tilt variation so all six degrees of
/// freedom are exercised; the camera turns 360 degrees about the vertical over the loop.
std::vector<Transform> circle(int n) {
  std::vector<Transform> truth;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    truth.push_back(pose(2.0 * std::cos(a), 0.2 * std::sin(3 * a), 2.0 * std::sin(a), -a, 5 * kDeg * std::sin(2 * a)));
  }
  return truth;
}

struct NoisyLoop {
  std::vector<Transform> truth;
  std::vector<Transform> odometry;  // poses chained from the noisy odometry (the initial guess)
  std::vector<PoseGraphEdge> edges;
};

/// 100 poses and odometry edges i -> i+1 that drift as a tracker does: a bias of 0.1 degrees of yaw
/// and 0.03 degrees of roll per step (about 10 degrees over the loop) plus seeded noise (2 mm and
/// 0.05 degrees per axis); and one exact loop edge 99 -> 0. The odometry's information states
/// sigmas of 5 mm and 0.15 degrees, which cover the bias: an information matrix that claimed
/// only the noise would make a robust loss reject the correct loop edge as an outlier (rightly,
/// by that claim).
NoisyLoop noisyLoop() {
  NoisyLoop loop;
  const int n = 100;
  loop.truth = circle(n);
  std::mt19937 rng(15);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::Matrix3d bias = pose(0, 0, 0, 0.1 * kDeg, 0.0, 0.03 * kDeg).linear();
  loop.odometry = {loop.truth[0]};
  for (int i = 0; i + 1 < n; ++i) {
    Transform T_i_j = loop.truth[i].inverse() * loop.truth[i + 1];
    const Eigen::Vector3d dt(noise(rng), noise(rng), noise(rng)), dr(noise(rng), noise(rng), noise(rng));
    T_i_j.translation() += 0.002 * dt;
    T_i_j.linear() =
        T_i_j.linear() * bias * Eigen::AngleAxisd(0.05 * kDeg * dr.norm(), dr.normalized()).toRotationMatrix();
    loop.edges.push_back({i, i + 1, T_i_j, information(0.005, 0.15 * kDeg), false});
    loop.odometry.push_back(loop.odometry.back() * T_i_j);
  }
  loop.edges.push_back({n - 1, 0, loop.truth[n - 1].inverse() * loop.truth[0], information(0.002, 0.05 * kDeg), true});
  return loop;
}

// The odometry drifts by 0.4 m and 10 degrees by the loop's end (checked, so the test keeps
// meaning something if the generator changes). The loop edge spreads the drift over the loop:
// every pose ends within 5 cm and 1.2 degrees of the truth (measured 3.2 cm, 0.73 degrees). What
// is left is the noise no loop edge can remove (a random walk of 50 steps of 2 mm and 0.05 degrees
// per axis: ~0.45 degrees at mid-loop) and the bias, which least squares spreads evenly over the
// edges but which does not commute with the turning (1 cm and 0.5 degrees without noise).
TEST(PoseGraph, LoopEdgePullsANoisyLoopBackToTheTruth) {
  NoisyLoop loop = noisyLoop();
  const double drift_m = maxPositionError(loop.odometry, loop.truth);
  ASSERT_GT(drift_m, 0.3) << "the odometry no longer drifts: the test would be empty";
  ASSERT_GT(maxAngleError(loop.odometry, loop.truth), 8 * kDeg);
  std::vector<Transform> nodes = loop.odometry;
  const PoseGraphResult result = optimizePoseGraph(&nodes, loop.edges);
  EXPECT_TRUE(result.converged);
  EXPECT_LT(result.final_cost, result.initial_cost);
  EXPECT_GT(result.iterations, 0);
  EXPECT_LT(maxPositionError(nodes, loop.truth), 0.05) << "odometry drift was " << drift_m << " m";
  EXPECT_LT(maxAngleError(nodes, loop.truth), 1.2 * kDeg);
  // Both losses close a correct loop, although its residual starts far above the robust scale.
  for (RobustLoss loss : {RobustLoss::kHuber, RobustLoss::kCauchy}) {
    PoseGraphOptions options;
    options.robust_loss = loss;
    std::vector<Transform> robust = loop.odometry;
    optimizePoseGraph(&robust, loop.edges, options);
    EXPECT_LT(maxPositionError(robust, loop.truth), 0.05) << (loss == RobustLoss::kHuber ? "Huber" : "Cauchy");
  }
}

// Exact measurements from a perturbed start: the optimum is the truth itself.
TEST(PoseGraph, ExactMeasurementsRecoverTheTruth) {
  const std::vector<Transform> truth = circle(30);
  std::vector<PoseGraphEdge> edges;
  for (int i = 0; i < 30; ++i)
    for (int step : {1, 7}) {
      const int j = (i + step) % 30;
      edges.push_back({i, j, truth[i].inverse() * truth[j], information(0.01, 0.01), false});
    }
  std::vector<Transform> nodes = truth;
  for (size_t i = 1; i < nodes.size(); ++i) nodes[i] = nodes[i] * pose(0.1, -0.05, 0.08, 6 * kDeg, -4 * kDeg, 3 * kDeg);
  optimizePoseGraph(&nodes, edges);
  EXPECT_LT(maxPositionError(nodes, truth), 1e-6);
  EXPECT_LT(maxAngleError(nodes, truth), 1e-6);
}

// A false loop closure: edge 25 -> 75 claims the two poses (4 m apart across the circle) are the
// same place. With the robust loss (Cauchy, the default) the result stays within 5 mm of the
// solution without that edge (measured 0.8 mm); without it, the loop is crushed by metres.
TEST(PoseGraph, RobustLossDownWeightsAWrongLoopEdge) {
  NoisyLoop loop = noisyLoop();
  std::vector<Transform> reference = loop.odometry;
  optimizePoseGraph(&reference, loop.edges);
  loop.edges.push_back({25, 75, Transform::Identity(), information(0.01, 0.5 * kDeg), true});

  std::vector<Transform> robust = loop.odometry;
  const PoseGraphResult result = optimizePoseGraph(&robust, loop.edges);
  EXPECT_LT(maxPositionError(robust, reference), 0.005);
  // The edge statistics tell the outlier apart: the false edge is ~4 m off at 1 cm sigma.
  ASSERT_EQ(result.edge_chi2.size(), loop.edges.size());
  EXPECT_GT(result.edge_chi2.back(), 1e4);
  EXPECT_LT(result.edge_chi2[loop.edges.size() - 2], 3.5 * 3.5) << "the correct loop edge";
  EXPECT_LT(maxPositionError(robust, loop.truth), 0.05);

  for (PoseGraphEdge& e : loop.edges) e.robust = false;
  std::vector<Transform> plain = loop.odometry;
  optimizePoseGraph(&plain, loop.edges);
  EXPECT_GT(maxPositionError(plain, loop.truth), 1.0);

  // Huber's pull is bounded, not vanishing: it bends the loop less, but still by ~10 cm (1.8 m
  // without a robust loss). Hence Cauchy is the default.
  for (PoseGraphEdge& e : loop.edges) e.robust = true;
  PoseGraphOptions huber_options;
  huber_options.robust_loss = RobustLoss::kHuber;
  std::vector<Transform> huber = loop.odometry;
  optimizePoseGraph(&huber, loop.edges, huber_options);
  EXPECT_LT(maxPositionError(huber, loop.truth), 0.25 * maxPositionError(plain, loop.truth));
  EXPECT_GT(maxPositionError(huber, loop.truth), 0.05);
}

// Fixed nodes keep their pose bit for bit; the others move.
TEST(PoseGraph, FixedNodesStayPut) {
  const NoisyLoop loop = noisyLoop();
  PoseGraphOptions options;
  options.fixed_nodes = {10, 60};
  std::vector<Transform> nodes = loop.odometry;
  optimizePoseGraph(&nodes, loop.edges, options);
  for (int i : {10, 60}) EXPECT_TRUE(nodes[i].isApprox(loop.odometry[i], 0.0)) << "node " << i;
  EXPECT_GT((nodes[0].translation() - loop.odometry[0].translation()).norm(), 1e-3) << "node 0 is free here";

  std::vector<Transform> default_gauge = loop.odometry;
  optimizePoseGraph(&default_gauge, loop.edges);
  EXPECT_TRUE(default_gauge[0].isApprox(loop.odometry[0], 0.0));
}

TEST(PoseGraph, SameInputSameOutput) {
  const NoisyLoop loop = noisyLoop();
  std::vector<Transform> a = loop.odometry, b = loop.odometry;
  optimizePoseGraph(&a, loop.edges);
  optimizePoseGraph(&b, loop.edges);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].matrix(), b[i].matrix()) << "node " << i;
}

// A node that no edge reaches keeps its pose exactly.
TEST(PoseGraph, UnreachedNodesKeepTheirPose) {
  std::vector<Transform> nodes = {Transform::Identity(), pose(1, 0, 0, 0.1), pose(3, 2, 1, 0.7, 0.2, 0.3)};
  const Transform lonely = nodes[2];
  const std::vector<PoseGraphEdge> edges = {{0, 1, pose(0.5, 0, 0, 0), information(0.01, 0.01), false}};
  optimizePoseGraph(&nodes, edges);
  EXPECT_TRUE(nodes[2].isApprox(lonely, 0.0));
}

TEST(PoseGraph, RefusesInvalidInput) {
  const auto refuses = [](std::vector<Transform> nodes, std::vector<PoseGraphEdge> edges, PoseGraphOptions options,
                          const std::string& message) {
    try {
      optimizePoseGraph(&nodes, edges, options);
      ADD_FAILURE() << "accepted, expected: " << message;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(e.what(), message);
    }
  };
  const std::vector<Transform> two = {Transform::Identity(), pose(1, 0, 0, 0)};
  const PoseGraphEdge good{0, 1, pose(1, 0, 0, 0), information(0.01, 0.01), false};
  PoseGraphEdge e = good;
  e.to = 2;
  refuses(two, {good, e}, {}, "pose graph edge 1 (0 -> 2): refers to a missing node (the graph has 2 nodes)");
  e = good;
  e.from = -1;
  refuses(two, {e}, {}, "pose graph edge 0 (-1 -> 1): refers to a missing node (the graph has 2 nodes)");
  e = good;
  e.to = 0;
  refuses(two, {e}, {}, "pose graph edge 0 (0 -> 0): joins a node to itself");
  e = good;
  e.T_from_to.translation().x() = NAN;
  refuses(two, {e}, {}, "pose graph edge 0 (0 -> 1): relative pose is not a finite rigid transform");
  e = good;
  e.T_from_to.linear() *= 2.0;
  refuses(two, {e}, {}, "pose graph edge 0 (0 -> 1): relative pose is not a finite rigid transform");
  e = good;
  e.information(2, 2) = INFINITY;
  refuses(two, {e}, {}, "pose graph edge 0 (0 -> 1): information matrix is not finite");
  e = good;
  e.information(0, 3) = 5.0;
  refuses(two, {e}, {}, "pose graph edge 0 (0 -> 1): information matrix is not symmetric");
  e = good;
  e.information(4, 4) = -1.0;
  refuses(two, {e}, {}, "pose graph edge 0 (0 -> 1): information matrix is not positive definite");
  e.information.setZero();
  refuses(two, {e}, {}, "pose graph edge 0 (0 -> 1): information matrix is not positive definite");
  std::vector<Transform> bad_node = two;
  bad_node[1].translation().y() = INFINITY;
  refuses(bad_node, {good}, {}, "pose graph node 1: pose is not a finite rigid transform");
  PoseGraphOptions options;
  options.fixed_nodes = {0, 5};
  refuses(two, {good}, options, "pose graph: fixed node 5 does not exist (the graph has 2 nodes)");
  options = {};
  options.robust_scale = 0.0;
  refuses(two, {good}, options, "pose graph: robust_scale must be a positive number");
  options.robust_scale = NAN;
  refuses(two, {good}, options, "pose graph: robust_scale must be a positive number");
}

}  // namespace
}  // namespace vdmap
