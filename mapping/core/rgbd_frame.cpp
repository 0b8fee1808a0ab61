#include "mapping/core/rgbd_frame.h"

namespace vdmap {

ColoredPointCloud toPointCloud(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range) {
  ColoredPointCloud cloud;
  const bool has_rgb = !frame.rgb.empty();
  const double inv_scale = 1.0 / camera.depth_scale;
  cloud.points.reserve(frame.depth.total());
  cloud.colors.reserve(frame.depth.total());
  for (int v = 0; v < frame.depth.rows; ++v) {
    const auto* d_row = frame.depth.ptr<std::uint16_t>(v);
    const auto* c_row = has_rgb ? frame.rgb.ptr<cv::Vec3b>(v) : nullptr;
    for (int u = 0; u < frame.depth.cols; ++u) {
      const double d = d_row[u] * inv_scale;
      if (d_row[u] == 0 || !range.contains(d)) continue;
      cloud.points.push_back(camera.backProject(u, v, d).cast<float>());
      const cv::Vec3b c = has_rgb ? c_row[u] : cv::Vec3b(255, 255, 255);
      cloud.colors.push_back({c[0], c[1], c[2]});
    }
  }
  return cloud;
}

}  // namespace vdmap
