#include "mapping/core/colour_registration.h"

#include <opencv2/imgproc.hpp>

namespace vdmap {

cv::Mat registerColour(const cv::Mat& rgb, const cv::Mat& depth, const PinholeCamera& depth_camera,
                       const ColourCamera& colour) {
  CV_Assert(rgb.type() == CV_8UC3 && !rgb.empty() && depth.type() == CV_16UC1);
  // The colour camera's view of depth pixel (u, v) at depth z: R * z * ray(u, v) + t, divided by
  // z (projection does not mind the scale): R * ray + t / z, with R * ray linear along a row.
  const Eigen::Matrix3f R = colour.T_colour_depth.linear().cast<float>();
  const Eigen::Vector3f t = colour.T_colour_depth.translation().cast<float>();
  const float fx = static_cast<float>(colour.fx), fy = static_cast<float>(colour.fy);
  const float cx = static_cast<float>(colour.cx), cy = static_cast<float>(colour.cy);
  const float per_unit = static_cast<float>(depth_camera.depth_scale);
  const Eigen::Vector3f step = R.col(0) / static_cast<float>(depth_camera.fx);
  cv::Mat map_u(depth.size(), CV_32F), map_v(depth.size(), CV_32F);
  for (int v = 0; v < depth.rows; ++v) {
    const std::uint16_t* d = depth.ptr<std::uint16_t>(v);
    float* mu = map_u.ptr<float>(v);
    float* mv = map_v.ptr<float>(v);
    const float y = static_cast<float>((v - depth_camera.cy) / depth_camera.fy);
    const Eigen::Vector3f row = R.col(1) * y + R.col(2) - step * static_cast<float>(depth_camera.cx);
    for (int u = 0; u < depth.cols; ++u) {
      Eigen::Vector3f p = row + step * static_cast<float>(u);
      if (d[u] > 0) p += t * (per_unit / d[u]);  // without depth: the ray at infinity
      // Behind the colour camera (never for a real rig): a pixel far outside, clamped to the edge.
      const bool in_front = p.z() > 1e-6f;
      const float inv_z = in_front ? 1.0f / p.z() : 0.0f;
      mu[u] = in_front ? fx * p.x() * inv_z + cx : -1.0f;
      mv[u] = in_front ? fy * p.y() * inv_z + cy : -1.0f;
    }
  }
  cv::Mat registered;
  cv::remap(rgb, registered, map_u, map_v, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return registered;
}

}  // namespace vdmap
