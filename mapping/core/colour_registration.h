#pragma once
// Colour registered to depth. Most RGB-D recordings store the colour image in the depth camera's
// pixels already (TUM, ICL-NUIM, Replica renders); some do not: 7-Scenes keeps the Kinect v1's
// colour camera (525 px focal, 2.5 cm to the side) and its depth camera (585 px) apart. Used as
// if registered, a colour pixel is read against the wrong depth and the wrong focal length: ORB
// features see every rotation ~10 % too small and pull the tracked rotation off, and colours
// slide off depth edges. Registration resamples the colour image at the depth camera's pixels.
#include <opencv2/core.hpp>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"

namespace vdmap {

/// A colour camera beside the depth camera: its intrinsics (fx, fy, cx, cy), its image size
/// and where it sits, T_colour_depth (depth camera frame -> colour camera frame).
struct ColourCamera {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  Transform T_colour_depth = Transform::Identity();
  int width = 0, height = 0;  ///< px; 0: the depth camera's size (ScanNet's colour is 1296x968 beside 640x480)

  bool operator==(const ColourCamera& o) const {
    return fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy && width == o.width && height == o.height &&
           T_colour_depth.matrix() == o.T_colour_depth.matrix();
  }
};

/// The colour of every depth pixel: its point (from `depth`, raw units of `depth_camera`)
/// projected into the colour camera and sampled there (bilinear, edges clamped). A pixel without
/// depth takes the colour along its ray at infinity (the rotation alone), so the image has no
/// holes for the feature detector to find corners at. `depth` has the depth camera's size, `rgb`
/// the colour camera's; the result has the depth camera's.
cv::Mat registerColour(const cv::Mat& rgb, const cv::Mat& depth, const PinholeCamera& depth_camera,
                       const ColourCamera& colour);

}  // namespace vdmap
