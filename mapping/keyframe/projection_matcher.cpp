#include "mapping/keyframe/projection_matcher.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace vdmap {
namespace {

// Runtime dispatch between a POPCNT build and the baseline of the functions whose inner loop is
// orbDistance() (POPCNT is several times faster than OpenCV's SSE2 table popcount).
#define VDMAP_POPCNT_CLONES __attribute__((target_clones("popcnt", "default")))

// Keeps the best two of a stream of (row, distance); ties keep the lower row.
inline void offer(BestTwo* b, int row, int d) {
  if (d < b->best_distance || (d == b->best_distance && row < b->best)) {
    b->second_distance = b->best_distance;
    b->best_distance = d;
    b->best = row;
  } else if (d < b->second_distance) {
    b->second_distance = d;
  }
}

}  // namespace

VDMAP_POPCNT_CLONES
BestTwo bestTwoOf(const std::uint8_t* query, const cv::Mat& descriptors) {
  assert(descriptors.empty() || (descriptors.type() == CV_8UC1 && descriptors.cols == 32));
  BestTwo b;
  for (int r = 0; r < descriptors.rows; ++r) offer(&b, r, orbDistance(query, descriptors.ptr<std::uint8_t>(r)));
  return b;
}

KeypointGrid::KeypointGrid(const std::vector<cv::KeyPoint>& keypoints, const PinholeCamera& camera, int cell_px)
    : keypoints_(&keypoints), cell_px_(cell_px), cols_((camera.width + cell_px - 1) / cell_px),
      rows_((camera.height + cell_px - 1) / cell_px) {
  // Counting sort by bucket; a stable pass keeps each bucket's indices ascending.
  auto bucket = [&](const cv::KeyPoint& k) {
    const int c = std::clamp(static_cast<int>(k.pt.x / cell_px_), 0, cols_ - 1);
    const int r = std::clamp(static_cast<int>(k.pt.y / cell_px_), 0, rows_ - 1);
    return r * cols_ + c;
  };
  start_.assign(static_cast<std::size_t>(cols_) * rows_ + 1, 0);
  for (const cv::KeyPoint& k : keypoints) ++start_[bucket(k) + 1];
  for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
  index_.resize(keypoints.size());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < keypoints.size(); ++i) index_[fill[bucket(keypoints[i])]++] = static_cast<int>(i);
}

VDMAP_POPCNT_CLONES
std::vector<FeatureMatch> matchByProjection(const FrameFeatures& K, const Transform& T_F_K, const FrameFeatures& F,
                                            const KeypointGrid& grid, const PinholeCamera& camera,
                                            const ProjectionSearchParams& params) {
  std::vector<FeatureMatch> matches;
  for (std::size_t i = 0; i < K.size(); ++i) {
    if (K.depth_m[i] <= 0.0f) continue;
    const cv::Point2f& pt = K.keypoints[i].pt;
    const Eigen::Vector3d p_F = T_F_K * camera.backProject(pt.x, pt.y, K.depth_m[i]);
    if (p_F.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p_F);
    if (!camera.inImage(uv.x(), uv.y(), params.radius_px)) continue;
    BestTwo b;
    const std::uint8_t* d = K.descriptors.ptr<std::uint8_t>(static_cast<int>(i));
    grid.forEachNear(uv.x(), uv.y(), std::max(params.radius_px, params.context_radius_px),
                     [&](int j) { offer(&b, j, orbDistance(d, F.descriptors.ptr<std::uint8_t>(j))); });
    if (!b.passes(params.max_hamming, params.lowe_ratio)) continue;
    const cv::Point2f& q = F.keypoints[static_cast<std::size_t>(b.best)].pt;
    const double du = q.x - uv.x(), dv = q.y - uv.y();
    if (du * du + dv * dv <= params.radius_px * params.radius_px)
      matches.push_back({static_cast<int>(i), b.best, b.best_distance});
  }
  return matches;
}

}  // namespace vdmap
