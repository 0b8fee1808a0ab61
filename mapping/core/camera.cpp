#include "mapping/core/camera.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace vdmap {

Eigen::Matrix3d PinholeCamera::backProjectJacobian(double u, double v, double depth_m) const {
  Eigen::Matrix3d J;
  J << depth_m / fx, 0.0, (u - cx) / fx,  //
      0.0, depth_m / fy, (v - cy) / fy,   //
      0.0, 0.0, 1.0;
  return J;
}

void PinholeCamera::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("camera: " + what); };
  if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide)
    fail("image size " + std::to_string(width) + "x" + std::to_string(height) + " must be within 1.." +
         std::to_string(kMaxImageSide));
  if (!(std::isfinite(fx) && fx > 0) || !(std::isfinite(fy) && fy > 0))
    fail("focal lengths fx, fy must be positive and finite");
  if (!std::isfinite(cx) || !std::isfinite(cy)) fail("principal point cx, cy must be finite");
  // The principal point is where the optical axis meets the image: a calibration puts it near the
  // centre, never outside (a cx typed for another image size would project every point off it).
  if (!(cx >= 0.0 && cx <= width && cy >= 0.0 && cy <= height)) {
    char text[160];
    std::snprintf(text, sizeof text, "principal point (cx %g, cy %g) must lie within the %dx%d image", cx, cy, width,
                  height);
    fail(text);
  }
  if (!(std::isfinite(depth_scale) && depth_scale > 0)) fail("depth_scale must be positive");
}

}  // namespace vdmap
