#include "mapping/tracking/relative_pose.h"

#include <cmath>
#include <functional>

#include <Eigen/Cholesky>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "mapping/keyframe/covisibility.h"
#include "mapping/keyframe/projection_matcher.h"

namespace vdmap {
namespace {

// Keyframe points with depth (keyframe frame) and the frame pixels they were matched to.
struct Correspondences {
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  void add(const FrameFeatures& K, std::size_t i, const cv::Point2f& pixel, const PinholeCamera& camera) {
    const cv::Point2f& pt = K.keypoints[i].pt;
    const Eigen::Vector3d p = camera.backProject(pt.x, pt.y, K.depth_m[i]);
    object.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    image.push_back(pixel);
  }
  std::size_t size() const { return object.size(); }
};

// Brute-force 2-NN with the ratio test over every keypoint of K with depth.
Correspondences bruteForceMatches(const FrameFeatures& K, const FrameFeatures& F, const PnpParams& params,
                                  const PinholeCamera& camera) {
  Correspondences out;
  if (K.size() == 0 || F.size() < 2) return out;
  for (const cv::DMatch& best : ratioTestMatches(K, F, params.max_hamming, params.lowe_ratio))
    if (K.depth_m[static_cast<std::size_t>(best.queryIdx)] > 0.0f)
      out.add(K, static_cast<std::size_t>(best.queryIdx), F.keypoints[static_cast<std::size_t>(best.trainIdx)].pt,
              camera);
  return out;
}

// K's keypoints with depth matched near where the prior T_F_K projects them (matchByProjection).
Correspondences projectionMatches(const FrameFeatures& K, const FrameFeatures& F, const Transform& T_F_K,
                                  const PnpParams& params, const PinholeCamera& camera) {
  Correspondences out;
  ProjectionSearchParams search;
  search.radius_px = params.search_radius_px;
  search.context_radius_px = 2 * params.search_radius_px;
  search.max_hamming = params.max_hamming;
  search.lowe_ratio = params.lowe_ratio;
  for (const FeatureMatch& m : matchByProjection(K, T_F_K, F, KeypointGrid(F.keypoints, camera), camera, search))
    out.add(K, static_cast<std::size_t>(m.keyframe), F.keypoints[static_cast<std::size_t>(m.frame)].pt, camera);
  return out;
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

// The correspondences whose reprojection at T_F_K lies within `px`.
std::vector<int> inliersAt(const Transform& T_F_K, const Correspondences& c, const PinholeCamera& camera, double px) {
  std::vector<int> out;
  for (std::size_t k = 0; k < c.size(); ++k) {
    const Eigen::Vector3d y = T_F_K * Eigen::Vector3d(c.object[k].x, c.object[k].y, c.object[k].z);
    if (y.z() <= 0) continue;
    const Eigen::Vector2d uv = camera.project(y);
    if ((uv - Eigen::Vector2d(c.image[k].x, c.image[k].y)).squaredNorm() <= px * px) out.push_back(static_cast<int>(k));
  }
  return out;
}

// Gauss-Newton on the reprojection errors of `inliers` from T_F_K (what cv::solvePnPRefineLM
// does, without its cv::Mat overhead, which made it a sixth of the tracking's time): steps
// T_F_K <- exp(xi) T_F_K until a step is below 1e-7 or 10 steps; a singular system stops it.
Transform refineReprojection(const Transform& T_F_K, const Correspondences& c, const PinholeCamera& camera,
                             const std::vector<int>& inliers) {
  Transform T = T_F_K;
  for (int step = 0; step < 10; ++step) {
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    for (const int k : inliers) {
      const Eigen::Vector3d y = T * Eigen::Vector3d(c.object[k].x, c.object[k].y, c.object[k].z);
      if (y.z() <= 0) continue;
      const double iz = 1.0 / y.z();
      const Eigen::Vector2d e(camera.fx * y.x() * iz + camera.cx - c.image[k].x,
                              camera.fy * y.y() * iz + camera.cy - c.image[k].y);
      Eigen::Matrix<double, 2, 3> P;
      P << camera.fx * iz, 0, -camera.fx * y.x() * iz * iz, 0, camera.fy * iz, -camera.fy * y.y() * iz * iz;
      Eigen::Matrix3d minus_skew_y;  // d(y)/d(phi) for y <- y + phi x y
      minus_skew_y << 0, y.z(), -y.y(), -y.z(), 0, y.x(), y.y(), -y.x(), 0;
      Eigen::Matrix<double, 2, 6> J;
      J.leftCols<3>() = P;
      J.rightCols<3>() = P * minus_skew_y;
      H.noalias() += J.transpose() * J;
      g.noalias() += J.transpose() * e;
    }
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(H);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 1e-12).all()) break;
    const Eigen::Matrix<double, 6, 1> xi = -ldlt.solve(g);
    if (!xi.allFinite()) break;
    T = stepTransform(xi) * T;
    T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();  // exactly a rotation
    if (xi.norm() < 1e-7) break;
  }
  return T;
}

// T_F_K refined from the prior's inverse: Gauss-Newton on the correspondences within 10 px of where the
// prior puts them (it is some px off), then again on those within px. nullopt when fewer than 4.
std::optional<Transform> refineFromPrior(const Transform& prior_T_K_C, const Correspondences& c,
                                         const PinholeCamera& camera, double px, std::vector<int>* inliers) {
  Transform T = prior_T_K_C.inverse();
  *inliers = inliersAt(T, c, camera, 10 * px);
  for (int pass = 0; pass < 2; ++pass) {
    if (inliers->size() < 4) return std::nullopt;
    T = refineReprojection(T, c, camera, *inliers);
    *inliers = inliersAt(T, c, camera, px);
  }
  if (inliers->size() < 4) return std::nullopt;
  return T;
}

// T_F_K by PnP RANSAC (EPnP on 5-point samples: AP3P picked wrong poses on the box room that
// explained a sixth of the matches while the truth explained all; then Gauss-Newton on the inliers). A
// scene that is mostly one plane has a second, mirrored PnP solution that explains the matches
// almost as well: with a prior, Gauss-Newton also starts from it (on the matches it explains), and the
// prior's solution is kept when it explains nearly as many matches (95%). A solution `plausible`
// rejects (the motion check) is not a candidate.
std::optional<Transform> solvePnpRansac(const Correspondences& c, const PinholeCamera& camera, const PnpParams& params,
                                        const std::optional<Transform>& prior_T_K_C,
                                        const std::function<bool(const Transform& T_F_K)>& plausible,
                                        std::vector<int>* inliers) {
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  // A fixed seed: cv::solvePnPRansac draws from cv::theRNG(), which is per thread and carries
  // state from earlier calls; reseeding makes every estimate depend only on its input.
  cv::theRNG().state = 0x12345678;
  const double px = params.ransac_reprojection_px;
  std::optional<Transform> best;
  if (cv::solvePnPRansac(c.object, c.image, K, cv::noArray(), rvec, tvec, false, params.ransac_iterations,
                         static_cast<float>(px), 0.99, *inliers, cv::SOLVEPNP_EPNP) &&
      inliers->size() >= 4) {
    best = refineReprojection(fromRvecTvec(rvec, tvec), c, camera, *inliers);
    *inliers = inliersAt(*best, c, camera, px);
    if (!plausible(*best)) best.reset(), inliers->clear();
  }
  std::vector<int> near;
  if (prior_T_K_C) {
    const std::optional<Transform> T = refineFromPrior(*prior_T_K_C, c, camera, px, &near);
    if (T && plausible(*T) && (!best || 20 * near.size() >= 19 * inliers->size())) best = T, *inliers = std::move(near);
  }
  if (!best || inliers->size() < 4) return std::nullopt;
  return best;
}

// The keyframe's PhotometricImage, decoded once: a per-thread cache of the last few keyframes
// (by their container's id, which no other container shares), as tracking compares each frame
// with the current keyframe and, now and then, a few others.
const PhotometricImage& keyframeImage(const Keyframe& K) {
  struct Entry {
    std::uint64_t id = 0;
    PhotometricImage image;
  };
  static thread_local std::array<Entry, 4> cache;
  static thread_local std::size_t next = 0;
  for (const Entry& e : cache)
    if (e.id == K.container.id()) return e.image;
  Entry& e = cache[next];
  next = (next + 1) % cache.size();
  e.id = K.container.id();
  e.image = photometricImage(K.rgb());
  return e.image;
}

// The rotation made exactly orthonormal again after many composed steps.
Transform orthonormalised(const Transform& T) {
  Transform out = Transform::Identity();
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  out.translation() = T.translation();
  return out;
}

}  // namespace

double translationBetween(const Transform& a, const Transform& b) { return (a.translation() - b.translation()).norm(); }

double degreesBetween(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

RelativePose estimateRelativePose(const Keyframe& K, const TrackingFrame& frame, const PinholeCamera& camera,
                                  const std::optional<Transform>& prior_T_K_C, const RelativePoseParams& params) {
  RelativePose out;
  const auto near = [&](const Transform& a, const Transform& b) {
    return translationBetween(a, b) <= params.max_jump_m && degreesBetween(a, b) <= params.max_jump_deg;
  };
  // PnP: from the prior on matches by projection when that explains enough of them; else
  // brute-force matches and RANSAC.
  const PnpParams& pp = params.pnp;
  const auto plausible = [&](const Transform& T_F_K) { return !prior_T_K_C || near(T_F_K.inverse(), *prior_T_K_C); };
  const FrameFeatures& F = *frame.features;
  Correspondences c;
  std::vector<int> pnp_inliers;
  std::optional<Transform> T_F_K;
  if (prior_T_K_C && pp.search_radius_px > 0) {
    c = projectionMatches(K.features, F, prior_T_K_C->inverse(), pp, camera);
    if (static_cast<int>(c.size()) >= pp.min_matches)
      T_F_K = refineFromPrior(*prior_T_K_C, c, camera, pp.ransac_reprojection_px, &pnp_inliers);
    if (T_F_K && (static_cast<int>(pnp_inliers.size()) < pp.min_inliers || !plausible(*T_F_K))) T_F_K.reset();
  }
  if (!T_F_K) {
    c = bruteForceMatches(K.features, F, pp, camera);
    if (static_cast<int>(c.size()) >= pp.min_matches)
      T_F_K = solvePnpRansac(c, camera, pp, prior_T_K_C, plausible, &pnp_inliers);
  }
  out.matches = static_cast<int>(c.size());
  std::optional<Transform> pnp;
  std::vector<FeatureObservation> inliers;
  if (T_F_K && T_F_K->matrix().allFinite()) {
    pnp = T_F_K->inverse();
    out.pnp_inliers = static_cast<int>(pnp_inliers.size());
    if (out.pnp_inliers < pp.min_inliers) {
      pnp.reset();
    } else {
      for (const int k : pnp_inliers)
        inliers.push_back({Eigen::Vector3d(c.object[k].x, c.object[k].y, c.object[k].z),
                           Eigen::Vector2d(c.image[k].x, c.image[k].y)});
    }
  }
  out.pnp_used = pnp.has_value();
  if (!pnp && !prior_T_K_C) return out;
  out.T_K_C = pnp ? *pnp : *prior_T_K_C;  // the estimate unless a trusted refinement replaces it
  if (params.dense_refinement && frame.points) {
    Transform seed = prior_T_K_C ? *prior_T_K_C : *pnp;
    if (pnp && prior_T_K_C &&
        (translationBetween(*pnp, seed) > params.seed_agreement_m ||
         degreesBetween(*pnp, seed) > params.seed_agreement_deg)) {
      // Both measured where they are (no step); the one the local map and the features support better is refined.
      NdtRefinementParams measure = params.dense;
      measure.iterations = 0;
      const auto support = [&](Transform T) {
        return refineAgainstLocalMap(K.container, *frame.points, inliers, &T, measure).support;
      };
      if (support(*pnp) >= support(seed)) seed = *pnp;
    }
    Transform refined = seed;
    const PhotometricPoints* points = params.photometric && !pnp && frame.photometric ? &frame.photometric() : nullptr;
    const PhotometricImage* image = points && !points->empty() ? &keyframeImage(K) : nullptr;
    std::optional<PhotometricTerm> photometric;
    if (image && !image->empty()) photometric.emplace(PhotometricTerm{*points, *image});
    out.dense = refineAgainstLocalMap(K.container, *frame.points, inliers, &refined, params.dense,
                                      photometric ? &*photometric : nullptr);
    out.dense_trusted = out.dense.inlierRatio() >= params.min_dense_inlier_ratio &&
                        out.dense.inliers >= params.min_dense_inliers && near(refined, seed);
    if (out.dense_trusted) out.T_K_C = orthonormalised(refined);
  }
  const bool dense_ok = out.dense_trusted || !params.dense_refinement;
  if (out.pnp_used && dense_ok) out.status = RelativePose::Status::kGood;
  else if (out.pnp_used || out.dense_trusted) out.status = RelativePose::Status::kWeak;
  return out;
}

}  // namespace vdmap
