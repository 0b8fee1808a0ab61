#pragma once
#include "mapping/core/camera.h"
#include "mapping/keyframe/frame_features.h"

namespace vdmap {

/// docs/method.md 5: when a keyframe's feature counts as re-observed in a frame.
struct CovisibilityParams {
  int max_hamming = 64;              ///< descriptor distance limit
  double lowe_ratio = 0.8;           ///< best / second-best distance must be below this
  double max_reprojection_px = 8.0;  ///< pose-consistency check for keypoints with depth
};

/// Pose pre-filter of the loop-closure and edge search (docs/method.md 5).
struct PosePrefilter {
  bool enabled = true;
  double max_distance_m = 3.0;
  double max_angle_deg = 90.0;
  /// True when keyframe pose T_W_K is close enough to frame pose T_W_F to be worth matching.
  bool accepts(const Transform& T_W_K, const Transform& T_W_F) const;
};

/// delta(F, K): the fraction of K's features re-observed in F (0 when K has none). A keypoint
/// with depth is matched by projection (matchByProjection(): the best descriptor within 48 px
/// of where the poses put it must lie within max_reprojection_px and pass the ratio test against
/// the second best of those 48 px); one without depth against all of F's descriptors. The
/// criteria of docs/method.md 5 keep their meaning; only the rivals of the ratio test come from 48 px
/// instead of the whole image, so delta is slightly above covisibilityBruteForce()'s and the
/// decision nearly always the same (test_projection_matcher; docs/notes/performance.md).
double covisibility(const FrameFeatures& keyframe, const Transform& T_W_K, const FrameFeatures& frame,
                    const Transform& T_W_F, const PinholeCamera& camera, const CovisibilityParams& params = {});

/// delta(F, K) as docs/method.md 5 words it, kept as the tests' oracle: cv::BFMatcher 2-NN of every
/// K descriptor over all of F's, ratio test, then the 8 px pose check. Far slower.
double covisibilityBruteForce(const FrameFeatures& keyframe, const Transform& T_W_K, const FrameFeatures& frame,
                              const Transform& T_W_F, const PinholeCamera& camera,
                              const CovisibilityParams& params = {});

/// The brute-force matches of docs/method.md 5: for each of K's descriptors its nearest of F's
/// (cv::BFMatcher 2-NN, Hamming) when within `max_hamming` and below `lowe_ratio` times the
/// second nearest; queryIdx indexes K, trainIdx F. Shared by covisibilityBruteForce() and the
/// tracker's PnP matches.
std::vector<cv::DMatch> ratioTestMatches(const FrameFeatures& K, const FrameFeatures& F, int max_hamming,
                                         double lowe_ratio);

/// Either of the two above (the decision takes the measure, so tests can run the oracle).
using CovisibilityMeasure = double (*)(const FrameFeatures&, const Transform&, const FrameFeatures&, const Transform&,
                                       const PinholeCamera&, const CovisibilityParams&);

/// An upper bound of covisibility() computed without matching: the fraction of K's features
/// that could be re-observed at all (without depth, or projecting in front of F's camera within
/// max_reprojection_px of its image). Exact pruning: covisibility() <= this.
double covisibilityBound(const FrameFeatures& keyframe, const Transform& T_W_K, const Transform& T_W_F,
                         const PinholeCamera& camera, const CovisibilityParams& params = {});

}  // namespace vdmap
