#pragma once
// Basic geometric types. Naming: T_A_B maps points from frame B into frame A
// (p_A = T_A_B * p_B); W world, C current camera, K keyframe camera.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vdmap {

/// A rigid transform in SE(3), double precision.
using Transform = Eigen::Isometry3d;

/// Valid depth interval in metres (docs/method.md 1: [0.1, 8.0] by default).
struct DepthRange {
  double min_m = 0.1;
  double max_m = 8.0;
  bool contains(double d) const { return d >= min_m && d <= max_m; }
};

/// True when every coefficient of the transform is finite and its rotation is orthonormal.
bool isValidTransform(const Transform& T, double tolerance = 1e-6);

}  // namespace vdmap
