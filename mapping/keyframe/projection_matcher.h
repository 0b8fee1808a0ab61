#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"
#include "mapping/keyframe/frame_features.h"

namespace vdmap {

/// Hamming distance of two 32-byte ORB descriptors. Inlined into the callers that are compiled
/// for POPCNT (target_clones with runtime dispatch, see projection_matcher.cpp): Debian's
/// OpenCV is built for the SSE2 baseline, whose Hamming distance is a table lookup.
inline int orbDistance(const std::uint8_t* a, const std::uint8_t* b) {
  std::uint64_t x[4], y[4];
  std::memcpy(x, a, 32);
  std::memcpy(y, b, 32);
  return __builtin_popcountll(x[0] ^ y[0]) + __builtin_popcountll(x[1] ^ y[1]) + __builtin_popcountll(x[2] ^ y[2]) +
         __builtin_popcountll(x[3] ^ y[3]);
}

/// The best and second-best distance of a descriptor to a set (kNoDistance when absent).
struct BestTwo {
  static constexpr int kNoDistance = 1 << 20;
  int best = -1;  ///< row of the best descriptor, -1 when the set is empty
  int best_distance = kNoDistance;
  int second_distance = kNoDistance;
  /// docs/method.md 5 descriptor test: best <= max_hamming and, when there is a second, best <
  /// ratio * second.
  bool passes(int max_hamming, double ratio) const {
    return best >= 0 && best_distance <= max_hamming &&
           (second_distance == kNoDistance || best_distance < ratio * second_distance);
  }
};

/// Best two of `query` (32 bytes) against every row of `descriptors` (CV_8U, 32 columns); ties
/// keep the lower row, as cv::BFMatcher does.
BestTwo bestTwoOf(const std::uint8_t* query, const cv::Mat& descriptors);

/// A frame's keypoints bucketed by image cell, for window look-ups around a predicted pixel.
/// Holds indices only; the keypoints must outlive it.
class KeypointGrid {
 public:
  KeypointGrid(const std::vector<cv::KeyPoint>& keypoints, const PinholeCamera& camera, int cell_px = 32);
  /// Calls visit(index) for every keypoint within `radius_px` of (u, v) (Euclidean, inclusive),
  /// bucket by bucket (not in index order).
  template <class Visit>
  void forEachNear(double u, double v, double radius_px, Visit&& visit) const {
    const int c0 = std::max(0, static_cast<int>(std::floor((u - radius_px) / cell_px_)));
    const int c1 = std::min(cols_ - 1, static_cast<int>(std::floor((u + radius_px) / cell_px_)));
    const int r0 = std::max(0, static_cast<int>(std::floor((v - radius_px) / cell_px_)));
    const int r1 = std::min(rows_ - 1, static_cast<int>(std::floor((v + radius_px) / cell_px_)));
    const double r2 = radius_px * radius_px;
    for (int r = r0; r <= r1; ++r)
      for (int s = start_[r * cols_ + c0], e = start_[r * cols_ + c1 + 1]; s < e; ++s) {
        const cv::Point2f& p = (*keypoints_)[static_cast<std::size_t>(index_[s])].pt;
        const double du = p.x - u, dv = p.y - v;
        if (du * du + dv * dv <= r2) visit(index_[s]);
      }
  }

 private:
  const std::vector<cv::KeyPoint>* keypoints_;
  int cell_px_, cols_, rows_;
  std::vector<int> start_;  ///< cols_ * rows_ + 1 offsets into index_
  std::vector<int> index_;  ///< keypoint indices, bucket by bucket, ascending in each
};

/// How a projected keypoint is matched (docs/method.md 5 criteria by default).
struct ProjectionSearchParams {
  double radius_px = 8.0;  ///< the match must lie this close to the predicted pixel
  /// The neighbourhood the best and second-best descriptor are taken from (>= radius_px): the
  /// best there must lie within radius_px and pass the ratio test against the second. Equal to
  /// radius_px it is ORB-SLAM's window search; the whole image is docs/method.md 5's brute-force
  /// 2-NN. Wider costs more candidates and rejects more ambiguous matches.
  double context_radius_px = 8.0;
  int max_hamming = 64;
  double lowe_ratio = 0.8;  ///< best < ratio * second-best; 1 disables
};

/// One correspondence: keyframe keypoint `keyframe`, frame keypoint `frame`.
struct FeatureMatch {
  int keyframe = -1;
  int frame = -1;
  int distance = 0;
};

/// Search by projection (as ORB-SLAM2's SearchByProjection): each of K's keypoints with depth
/// is back-projected, moved by T_F_K and projected into F; it matches the frame keypoint of the
/// smallest descriptor distance within `context_radius_px` of that pixel when that keypoint lies
/// within `radius_px` and its distance passes the descriptor test against the second best of
/// the context. Keypoints without depth, behind the camera or with none near give no match. At most one match per K keypoint,
/// in K's order; several may share a frame keypoint. T_F_K may be a predicted pose (tracking).
std::vector<FeatureMatch> matchByProjection(const FrameFeatures& keyframe, const Transform& T_F_K,
                                            const FrameFeatures& frame, const KeypointGrid& frame_grid,
                                            const PinholeCamera& camera, const ProjectionSearchParams& params = {});

}  // namespace vdmap
