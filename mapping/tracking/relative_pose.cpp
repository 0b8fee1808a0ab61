#include "mapping/tracking/relative_pose.h"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "mapping/keyframe/covisibility.h"

namespace vdmap {
namespace {

// K's keypoints with depth (3-D, keyframe frame) and the frame keypoints they match.
void matchWithDepth(const FrameFeatures& K, const FrameFeatures& F, const PnpParams& params,
                    const PinholeCamera& camera, std::vector<cv::Point3f>* object, std::vector<cv::Point2f>* image) {
  if (K.size() == 0 || F.size() < 2) return;
  for (const cv::DMatch& best : ratioTestMatches(K, F, params.max_hamming, params.lowe_ratio)) {
    const std::size_t i = static_cast<std::size_t>(best.queryIdx);
    if (K.depth_m[i] <= 0.0f) continue;
    const cv::Point2f& pt = K.keypoints[i].pt;
    const Eigen::Vector3d p = camera.backProject(pt.x, pt.y, K.depth_m[i]);
    object->emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    image->push_back(F.keypoints[best.trainIdx].pt);
  }
}

Transform fromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Matx33d R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d R_F_K;
  cv::cv2eigen(cv::Mat(R), R_F_K);
  Transform T_F_K = Transform::Identity();
  T_F_K.linear() = R_F_K;
  T_F_K.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  return T_F_K;
}

// The matches whose reprojection at T_F_K lies within `px`.
std::vector<int> inliersAt(const Transform& T_F_K, const std::vector<cv::Point3f>& object,
                           const std::vector<cv::Point2f>& image, const PinholeCamera& camera, double px) {
  std::vector<int> out;
  for (std::size_t k = 0; k < object.size(); ++k) {
    const Eigen::Vector3d y = T_F_K * Eigen::Vector3d(object[k].x, object[k].y, object[k].z);
    if (y.z() <= 0) continue;
    const Eigen::Vector2d uv = camera.project(y);
    if ((uv - Eigen::Vector2d(image[k].x, image[k].y)).squaredNorm() <= px * px) out.push_back(static_cast<int>(k));
  }
  return out;
}

// Levenberg-Marquardt on `inliers` from T_F_K; the inliers at the result.
Transform refineLm(const Transform& T_F_K, const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                   const PinholeCamera& camera, std::vector<int>* inliers) {
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  std::vector<cv::Point3f> o;
  std::vector<cv::Point2f> i;
  for (const int k : *inliers) o.push_back(object[k]), i.push_back(image[k]);
  cv::Mat R, rvec, tvec;
  cv::eigen2cv(Eigen::Matrix3d(T_F_K.linear()), R);
  cv::Rodrigues(R, rvec);
  tvec = (cv::Mat_<double>(3, 1) << T_F_K.translation().x(), T_F_K.translation().y(), T_F_K.translation().z());
  cv::solvePnPRefineLM(o, i, K, cv::noArray(), rvec, tvec);
  return fromRvecTvec(rvec, tvec);
}

// T_K_C by PnP RANSAC (EPnP on 5-point samples: AP3P picked wrong poses on the box room that
// explained a sixth of the matches while the truth explained all; then Levenberg-Marquardt on the inliers). A
// scene that is mostly one plane has a second, mirrored PnP solution that explains the matches
// almost as well: with a prior, LM also starts from it (on the matches it explains), and the
// prior's solution is kept when it explains nearly as many matches (95%).
std::optional<Transform> solvePnp(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                                  const PinholeCamera& camera, const PnpParams& params,
                                  const std::optional<Transform>& prior_T_K_C, int* inlier_count,
                                  std::vector<FeatureObservation>* inlier_observations) {
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  // A fixed seed: cv::solvePnPRansac draws from cv::theRNG(), which is per thread and carries
  // state from earlier calls; reseeding makes every estimate depend only on its input.
  cv::theRNG().state = 0x12345678;
  const double px = params.ransac_reprojection_px;
  std::optional<Transform> best;
  if (cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, params.ransac_iterations,
                         static_cast<float>(px), 0.99, inliers, cv::SOLVEPNP_EPNP) &&
      inliers.size() >= 4) {
    best = refineLm(fromRvecTvec(rvec, tvec), object, image, camera, &inliers);
    inliers = inliersAt(*best, object, image, camera, px);
  }
  if (prior_T_K_C) {
    Transform T = prior_T_K_C->inverse();
    std::vector<int> near = inliersAt(T, object, image, camera, 10 * px);  // the prior is some px off
    if (near.size() >= 4) {
      T = refineLm(T, object, image, camera, &near);
      near = inliersAt(T, object, image, camera, px);
      if (near.size() >= 4) {
        T = refineLm(T, object, image, camera, &near);
        near = inliersAt(T, object, image, camera, px);
        if (!best || 20 * near.size() >= 19 * inliers.size()) best = T, inliers = std::move(near);
      }
    }
  }
  if (!best || inliers.size() < 4 || !best->matrix().allFinite()) return std::nullopt;
  *inlier_count = static_cast<int>(inliers.size());
  for (const int k : inliers)
    inlier_observations->push_back({Eigen::Vector3d(object[k].x, object[k].y, object[k].z),
                                    Eigen::Vector2d(image[k].x, image[k].y)});
  return best->inverse();
}

// The rotation made exactly orthonormal again after many composed steps.
Transform orthonormalised(const Transform& T) {
  Transform out = Transform::Identity();
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  out.translation() = T.translation();
  return out;
}

}  // namespace

double translationBetween(const Transform& a, const Transform& b) {
  return (a.translation() - b.translation()).norm();
}

double degreesBetween(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

RelativePose estimateRelativePose(const Keyframe& K, const TrackingFrame& frame, const PinholeCamera& camera,
                                  const std::optional<Transform>& prior_T_K_C, const RelativePoseParams& params) {
  RelativePose out;
  const auto near = [&](const Transform& a, const Transform& b) {
    return translationBetween(a, b) <= params.max_jump_m && degreesBetween(a, b) <= params.max_jump_deg;
  };
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  matchWithDepth(K.features, *frame.features, params.pnp, camera, &object, &image);
  out.matches = static_cast<int>(object.size());
  std::optional<Transform> pnp;
  std::vector<FeatureObservation> inliers;
  if (out.matches >= params.pnp.min_matches) {
    pnp = solvePnp(object, image, camera, params.pnp, prior_T_K_C, &out.pnp_inliers, &inliers);
    if (pnp && (out.pnp_inliers < params.pnp.min_inliers || (prior_T_K_C && !near(*pnp, *prior_T_K_C)))) {
      pnp.reset();
      inliers.clear();
    }
  }
  out.pnp_used = pnp.has_value();
  std::vector<Transform> seeds;
  if (prior_T_K_C) seeds.push_back(*prior_T_K_C);
  if (pnp && (seeds.empty() || !params.dense_refinement || translationBetween(*pnp, seeds[0]) > params.seed_agreement_m ||
              degreesBetween(*pnp, seeds[0]) > params.seed_agreement_deg))
    seeds.insert(seeds.begin(), *pnp);  // PnP first: without refinement it is the estimate
  if (seeds.empty()) return out;
  out.T_K_C = seeds[0];
  if (params.dense_refinement && frame.points) {
    bool first = true;
    for (const Transform& seed : seeds) {
      Transform refined = seed;
      NdtRefinementResult dense = refineAgainstLocalMap(K.container, *frame.points, inliers, &refined, params.dense);
      if (!first && dense.support <= out.dense.support) continue;
      first = false;
      out.dense = dense;
      out.dense_trusted = dense.inlierRatio() >= params.min_dense_inlier_ratio &&
                          dense.inliers >= params.min_dense_inliers && near(refined, seed);
      out.T_K_C = out.dense_trusted ? orthonormalised(refined) : seeds[0];
    }
  }
  const bool dense_ok = out.dense_trusted || !params.dense_refinement;
  if (out.pnp_used && dense_ok) out.status = RelativePose::Status::kGood;
  else if (out.pnp_used || out.dense_trusted) out.status = RelativePose::Status::kWeak;
  return out;
}

}  // namespace vdmap
