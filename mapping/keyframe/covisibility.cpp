#include "mapping/keyframe/covisibility.h"

#include <cmath>

#include "mapping/keyframe/projection_matcher.h"

namespace vdmap {
namespace {

// Keyframe keypoint i (which has depth) in F's camera frame.
Eigen::Vector3d predictInFrame(const FrameFeatures& K, std::size_t i, const Transform& T_F_K,
                               const PinholeCamera& camera) {
  const cv::Point2f& pt = K.keypoints[i].pt;
  return T_F_K * camera.backProject(pt.x, pt.y, K.depth_m[i]);
}

// The neighbourhood of a projected keypoint whose best and second-best descriptor the ratio
// test compares (the best must also lie within max_reprojection_px). docs/method.md 5 takes both
// from the whole image. A smaller window has fewer rivals, so more ratio tests pass and delta
// rises above the brute-force decision's; the agreement with that decision grows with the window
// and levels off at 48 px (docs/notes/performance.md, "The keyframe decision", has the
// measurements). 48 px holds a couple of dozen keypoints of a 640x480 frame (more in textured
// spots): far fewer distances than brute force's 1000.
constexpr double kRatioContextPx = 48.0;

}  // namespace

bool PosePrefilter::accepts(const Transform& T_W_K, const Transform& T_W_F) const {
  if (!enabled) return true;
  if ((T_W_K.translation() - T_W_F.translation()).norm() > max_distance_m) return false;
  const double cos_angle = T_W_K.linear().col(2).dot(T_W_F.linear().col(2));
  return cos_angle >= std::cos(max_angle_deg * M_PI / 180.0) - 1e-12;
}

double covisibilityBound(const FrameFeatures& K, const Transform& T_W_K, const Transform& T_W_F,
                         const PinholeCamera& camera, const CovisibilityParams& params) {
  if (K.size() == 0) return 0.0;
  const Transform T_F_K = T_W_F.inverse() * T_W_K;
  std::size_t possible = 0;
  for (std::size_t i = 0; i < K.size(); ++i) {
    if (K.depth_m[i] <= 0.0f) {
      ++possible;
      continue;
    }
    const Eigen::Vector3d p_F = predictInFrame(K, i, T_F_K, camera);
    if (p_F.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p_F);
    if (camera.inImage(uv.x(), uv.y(), params.max_reprojection_px)) ++possible;
  }
  return static_cast<double>(possible) / static_cast<double>(K.size());
}

double covisibility(const FrameFeatures& K, const Transform& T_W_K, const FrameFeatures& F, const Transform& T_W_F,
                    const PinholeCamera& camera, const CovisibilityParams& params) {
  if (K.size() == 0 || F.size() < 2) return 0.0;
  const KeypointGrid grid(F.keypoints, camera);
  const ProjectionSearchParams search{params.max_reprojection_px, kRatioContextPx, params.max_hamming,
                                      params.lowe_ratio};
  std::size_t reobserved = matchByProjection(K, T_W_F.inverse() * T_W_K, F, grid, camera, search).size();
  for (std::size_t i = 0; i < K.size(); ++i)
    if (K.depth_m[i] <= 0.0f && bestTwoOf(K.descriptors.ptr<std::uint8_t>(static_cast<int>(i)), F.descriptors)
                                    .passes(params.max_hamming, params.lowe_ratio))
      ++reobserved;
  return static_cast<double>(reobserved) / static_cast<double>(K.size());
}

std::vector<cv::DMatch> ratioTestMatches(const FrameFeatures& K, const FrameFeatures& F, int max_hamming,
                                         double lowe_ratio) {
  std::vector<cv::DMatch> matches;
  if (K.size() == 0 || F.size() == 0) return matches;
  static thread_local cv::BFMatcher matcher(cv::NORM_HAMMING, false);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(K.descriptors, F.descriptors, knn, 2);
  for (const std::vector<cv::DMatch>& pair : knn) {
    if (pair.empty()) continue;
    const cv::DMatch& best = pair[0];
    if (best.distance > max_hamming) continue;
    if (pair.size() > 1 && !(best.distance < lowe_ratio * pair[1].distance)) continue;
    matches.push_back(best);
  }
  return matches;
}

double covisibilityBruteForce(const FrameFeatures& K, const Transform& T_W_K, const FrameFeatures& F,
                              const Transform& T_W_F, const PinholeCamera& camera, const CovisibilityParams& params) {
  if (K.size() == 0 || F.size() < 2) return 0.0;
  const Transform T_F_K = T_W_F.inverse() * T_W_K;
  const double max_sq = params.max_reprojection_px * params.max_reprojection_px;
  std::size_t reobserved = 0;
  for (const cv::DMatch& best : ratioTestMatches(K, F, params.max_hamming, params.lowe_ratio)) {
    const std::size_t i = static_cast<std::size_t>(best.queryIdx);
    if (K.depth_m[i] > 0.0f) {
      const Eigen::Vector3d p_F = predictInFrame(K, i, T_F_K, camera);
      if (p_F.z() <= 0.0) continue;
      const Eigen::Vector2d uv = camera.project(p_F);
      const cv::Point2f& q = F.keypoints[best.trainIdx].pt;
      if ((uv - Eigen::Vector2d(q.x, q.y)).squaredNorm() > max_sq) continue;
    }
    ++reobserved;
  }
  return static_cast<double>(reobserved) / static_cast<double>(K.size());
}

}  // namespace vdmap
