#pragma once
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "mapping/core/rgbd_frame.h"

namespace vdmap {

/// ORB keypoints of one frame with the depth measured at each (docs/method.md 5).
struct FrameFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;         ///< CV_8U, one 32-byte row per keypoint
  std::vector<float> depth_m;  ///< per keypoint; 0 when the depth image has no valid value there
  std::size_t size() const { return keypoints.size(); }
};

struct FeatureParams {
  int orb_features = 1000;  ///< docs/parameters.md
};

/// Detects ORB features in the frame's colour image. Deterministic for a given image. Not
/// thread-safe: one extractor per thread.
class FeatureExtractor {
 public:
  explicit FeatureExtractor(const FeatureParams& params = {});
  FrameFeatures extract(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range = {}) const;

 private:
  cv::Ptr<cv::ORB> orb_;
};

}  // namespace vdmap
