#pragma once
#include <Eigen/Core>

namespace vdmap {

/// Pinhole camera without distortion. Pixel (u, v): u right, v down, origin at the centre of
/// the top-left pixel. Points are in the camera frame (z forward), metres.
struct PinholeCamera {
  static constexpr int kMaxImageSide = 16384;  ///< px; validate() and camera files accept 1..this

  int width = 640;
  int height = 480;
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;
  /// Depth PNG units per metre (metres = value / depth_scale).
  double depth_scale = 5000.0;

  /// Pixel of a point with z > 0 (the caller checks z).
  Eigen::Vector2d project(const Eigen::Vector3d& p_C) const {
    return {fx * p_C.x() / p_C.z() + cx, fy * p_C.y() / p_C.z() + cy};
  }
  /// The point at pixel (u, v) with depth d (z, metres).
  Eigen::Vector3d backProject(double u, double v, double depth_m) const {
    return {(u - cx) * depth_m / fx, (v - cy) * depth_m / fy, depth_m};
  }
  /// d backProject / d(u, v, d) (docs/method.md 3).
  Eigen::Matrix3d backProjectJacobian(double u, double v, double depth_m) const;
  /// True when (u, v) rounds to a pixel inside the image grown by margin_px on every side.
  bool inImage(double u, double v, double margin_px = 0.0) const {
    const double lo = -0.5 - margin_px;
    return u >= lo && v >= lo && u < width - 0.5 + margin_px && v < height - 0.5 + margin_px;
  }
  /// Throws std::invalid_argument naming the first bad field (non-positive size/focal, a principal
  /// point outside the image, ...).
  void validate() const;

  bool operator==(const PinholeCamera&) const = default;
};

}  // namespace vdmap
