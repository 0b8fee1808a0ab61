#include "mapping/synth/depth_noise.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace vdmap {

DepthNoiseModel parseDepthNoiseModel(const std::string& name) {
  if (name == "none") return DepthNoiseModel::kNone;
  if (name == "nguyen2012") return DepthNoiseModel::kNguyen2012;
  throw std::invalid_argument("unknown noise model '" + name + "' (expected none or nguyen2012)");
}

cv::Mat simulateDepth(const cv::Mat& z_cos, double depth_scale, const DepthNoiseParams& params, int frame_index) {
  CV_Assert(z_cos.type() == CV_32FC2 && depth_scale > 0);
  const int rows = z_cos.rows, cols = z_cos.cols;
  cv::Mat out(rows, cols, CV_16UC1, cv::Scalar(0));
  const double max_raw = 65535.0 / depth_scale;  // the largest depth a 16-bit image can hold
  const double max_m = std::min(params.max_range_m, max_raw);
  if (params.model == DepthNoiseModel::kNone) {
    for (int v = 0; v < rows; ++v)
      for (int u = 0; u < cols; ++u) {
        const float z = z_cos.at<cv::Vec2f>(v, u)[0];
        if (z > 0 && z <= max_m) out.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(std::lround(z * depth_scale));
      }
    return out;
  }
  std::mt19937_64 rng(params.seed ^ (0x9e3779b97f4a7c15ull * static_cast<std::uint64_t>(frame_index + 1)));
  std::normal_distribution<double> normal(0.0, 1.0);
  const double min_cos = std::cos(params.max_incidence_deg * M_PI / 180.0);
  for (int v = 0; v < rows; ++v)
    for (int u = 0; u < cols; ++u) {
      // Draw all three numbers for every pixel so the stream does not depend on the scene.
      const double du = normal(rng) * params.lateral_sd_px, dv = normal(rng) * params.lateral_sd_px;
      const double n = normal(rng);
      const int su = std::clamp(u + static_cast<int>(std::lround(du)), 0, cols - 1);
      const int sv = std::clamp(v + static_cast<int>(std::lround(dv)), 0, rows - 1);
      const cv::Vec2f s = z_cos.at<cv::Vec2f>(sv, su);
      const double z = s[0];
      if (!(z > 0) || s[1] < min_cos) continue;
      const double noisy = z + n * nguyenAxialSd(z);
      if (noisy < params.min_range_m || noisy > max_m) continue;
      out.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(std::lround(noisy * depth_scale));
    }
  return out;
}

}  // namespace vdmap
