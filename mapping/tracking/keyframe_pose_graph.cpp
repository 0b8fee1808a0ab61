#include "mapping/tracking/keyframe_pose_graph.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <Eigen/Cholesky>

namespace vdmap {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

Matrix6d adjoint(const Transform& T) {
  const Eigen::Matrix3d R = T.linear();
  Matrix6d Ad = Matrix6d::Zero();
  Ad.topLeftCorner<3, 3>() = R;
  Ad.topRightCorner<3, 3>() = skew(T.translation()) * R;
  Ad.bottomRightCorner<3, 3>() = R;
  return Ad;
}

Matrix6d edgeInformation(const RelativePose& estimate, const EdgeNoise& floor) {
  const double st = floor.translation_m, sr = floor.rotation_deg * M_PI / 180.0;
  Matrix6d floor_cov = Matrix6d::Zero();
  floor_cov.diagonal() << st * st, st * st, st * st, sr * sr, sr * sr, sr * sr;
  if (!estimate.dense_trusted) return (9.0 * floor_cov).inverse();
  // exp(xi_K) T_K_C = T_K_C exp(xi_C) with xi_K = Ad(T_K_C) xi_C, so the information of xi_C
  // is Ad^T H Ad.
  const Matrix6d Ad = adjoint(estimate.T_K_C);
  Matrix6d info = Ad.transpose() * estimate.dense.information * Ad;
  info = 0.5 * (info + info.transpose());
  // The normal matrix can be singular along a direction the surfaces do not constrain (a single
  // wall): invert it regularised, the floor then bounds that direction.
  const Matrix6d cov = (info + 1e-9 * info.trace() * Matrix6d::Identity() + 1e-12 * Matrix6d::Identity()).inverse();
  Matrix6d out = (cov + floor_cov).inverse();
  return 0.5 * (out + out.transpose());
}

Matrix6d informationInFrame(const Matrix6d& info_B, const Transform& T_B_X) {
  // T_A_B exp(xi_B) T_B_X = T_A_X exp(xi_X) with xi_B = Ad(T_B_X) xi_X.
  const Matrix6d Ad = adjoint(T_B_X);
  const Matrix6d out = Ad.transpose() * info_B * Ad;
  return 0.5 * (out + out.transpose());
}

void KeyframePoseGraph::replaceMeasuredEdges(std::span<const PoseGraphEdge> edges) {
  std::set<std::pair<int, int>> pairs;
  for (const PoseGraphEdge& e : edges) pairs.insert(std::minmax(e.from, e.to));
  std::erase_if(edges_,
                [&pairs](const PoseGraphEdge& e) { return !e.robust && pairs.contains(std::minmax(e.from, e.to)); });
  edges_.insert(edges_.end(), edges.begin(), edges.end());
}

double KeyframePoseGraph::optimise(KeyframeGraph* graph, const PoseGraphOptions& options, PoseGraphResult* result,
                                   bool keep_before) {
  std::vector<Transform> poses;
  for (const Keyframe& k : graph->keyframes()) poses.push_back(k.T_W_K);
  const std::vector<Transform> start = poses;
  if (!keep_before || before_.size() != poses.size()) before_ = poses;
  const PoseGraphResult r = optimizePoseGraph(&poses, edges_, options);
  if (result) *result = r;
  double largest = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    // The optimiser's quaternions are unit to rounding; make the rotation exactly orthonormal.
    Transform T = Transform::Identity();
    T.linear() = Eigen::Quaterniond(poses[i].linear()).normalized().toRotationMatrix();
    T.translation() = poses[i].translation();
    largest = std::max(largest, (T.translation() - start[i].translation()).norm());
    graph->setKeyframePose(static_cast<int>(i), T);
  }
  return largest;
}

}  // namespace vdmap
