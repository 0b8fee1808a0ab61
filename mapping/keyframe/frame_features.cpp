#include "mapping/keyframe/frame_features.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

namespace vdmap {

FeatureExtractor::FeatureExtractor(const FeatureParams& params) : orb_(cv::ORB::create(params.orb_features)) {}

FrameFeatures FeatureExtractor::extract(const RgbdFrame& frame, const PinholeCamera& camera,
                                        const DepthRange& range) const {
  FrameFeatures features;
  if (frame.rgb.empty()) return features;
  cv::Mat gray;
  cv::cvtColor(frame.rgb, gray, cv::COLOR_RGB2GRAY);
  orb_->detectAndCompute(gray, cv::noArray(), features.keypoints, features.descriptors);
  features.depth_m.resize(features.keypoints.size(), 0.0f);
  if (frame.depth.empty()) return features;
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    const int u = static_cast<int>(std::lround(features.keypoints[i].pt.x));
    const int v = static_cast<int>(std::lround(features.keypoints[i].pt.y));
    if (u < 0 || v < 0 || u >= frame.depth.cols || v >= frame.depth.rows) continue;
    const double d = frame.depth.at<std::uint16_t>(v, u) / camera.depth_scale;
    if (frame.depth.at<std::uint16_t>(v, u) != 0 && range.contains(d)) features.depth_m[i] = static_cast<float>(d);
  }
  return features;
}

}  // namespace vdmap
