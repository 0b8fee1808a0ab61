#pragma once
// Test helpers for local maps: analytic scenes ray-cast into depth frames, and a slow,
// obviously-correct reference integrator (every point kept, two-pass statistics at the end)
// that is the oracle for the fast LocalMapIntegrator.
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "mapping/core/rgbd_frame.h"
#include "mapping/local_map/cell_stats.h"
#include "mapping/local_map/keyframe_container.h"
#include "tests/support/test_util.h"

namespace vdmap::test {

/// 640x480 "tum-default" camera at depth scale 5000 (0.2 mm per unit).
inline PinholeCamera sceneCamera() { return PinholeCamera{}; }

/// A surface for ray casting: distance t > 0 along a ray from `origin` (world), or nullopt.
using RayCaster = std::function<std::optional<double>(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir)>;

inline RayCaster planeScene(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  return [=](const Eigen::Vector3d& o, const Eigen::Vector3d& d) -> std::optional<double> {
    const double den = normal.dot(d);
    if (std::abs(den) < 1e-12) return std::nullopt;
    const double t = normal.dot(point - o) / den;
    return t > 0 ? std::optional<double>(t) : std::nullopt;
  };
}

inline RayCaster sphereScene(const Eigen::Vector3d& centre, double radius) {
  return [=](const Eigen::Vector3d& o, const Eigen::Vector3d& d) -> std::optional<double> {
    const Eigen::Vector3d oc = o - centre;
    const double b = oc.dot(d), c = oc.squaredNorm() - radius * radius, a = d.squaredNorm();
    const double disc = b * b - a * c;
    if (disc < 0) return std::nullopt;
    const double t = (-b - std::sqrt(disc)) / a;
    return t > 0 ? std::optional<double>(t) : std::nullopt;
  };
}

/// Axis-aligned box [lo, hi] (slab test).
inline RayCaster boxScene(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return [=](const Eigen::Vector3d& o, const Eigen::Vector3d& d) -> std::optional<double> {
    double t0 = 0.0, t1 = 1e30;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(d(k)) < 1e-15) {
        if (o(k) < lo(k) || o(k) > hi(k)) return std::nullopt;
        continue;
      }
      double a = (lo(k) - o(k)) / d(k), b = (hi(k) - o(k)) / d(k);
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    return (t0 <= t1 && t0 > 0) ? std::optional<double>(t0) : std::nullopt;
  };
}

/// Renders the depth of `scene` seen from T_W_C. noise_sd(depth) gives the standard deviation
/// (m) of Gaussian noise added to the depth z; values are then quantised to the depth scale.
/// Colour encodes the pixel position so colour means can be checked.
inline RgbdFrame renderFrame(const RayCaster& scene, const PinholeCamera& cam, const Transform& T_W_C,
                             const std::function<double(double)>& noise_sd, unsigned seed) {
  RgbdFrame f;
  f.T_W_C = T_W_C;
  f.depth = cv::Mat(cam.height, cam.width, CV_16UC1, cv::Scalar(0));
  f.rgb = cv::Mat(cam.height, cam.width, CV_8UC3);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Matrix3d R = T_W_C.linear();
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      f.rgb.at<cv::Vec3b>(v, u) = cv::Vec3b(u % 256, v % 256, (u + v) % 256);
      const Eigen::Vector3d ray_C = cam.backProject(u, v, 1.0);  // z = 1
      const auto t = scene(T_W_C.translation(), R * ray_C);
      if (!t) continue;
      const double d = *t + noise_sd(*t) * gauss(rng);  // t is the depth since ray_C.z = 1
      const double raw = std::round(d * cam.depth_scale);
      if (raw > 0 && raw < 65535) f.depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(raw);
    }
  return f;
}

/// Every point of every frame, grouped by the cell it falls into.
struct ReferenceMap {
  std::map<int, std::vector<Eigen::Vector3d>> points, colors;

  /// Per-pixel back-projection, transform and projection with the plain camera functions.
  void integrate(const RgbdFrame& frame, const PinholeCamera& cam, const Transform& T_W_K,
                 const KeyframeContainer& layout, const DepthRange& range = {}) {
    const Transform T_K_C = T_W_K.inverse() * frame.T_W_C;
    for (int v = 0; v < frame.depth.rows; ++v)
      for (int u = 0; u < frame.depth.cols; ++u) {
        const std::uint16_t raw = frame.depth.at<std::uint16_t>(v, u);
        const double d = raw / cam.depth_scale;
        if (raw == 0 || !range.contains(d)) continue;
        const Eigen::Vector3d p_K = T_K_C * cam.backProject(u, v, d);
        if (p_K.z() <= 0) continue;
        const Eigen::Vector2d uv = layout.camera().project(p_K);
        const int cell = layout.gridIndexOfPixel(uv.x(), uv.y());
        if (cell < 0) continue;
        const cv::Vec3b c = frame.rgb.at<cv::Vec3b>(v, u);
        points[cell].push_back(p_K);
        colors[cell].push_back(Eigen::Vector3d(c[0], c[1], c[2]));
      }
  }
  CellStats stats(int cell) const {
    CellStats s;
    mergeBatch(makeBatch(points.at(cell), colors.at(cell)), &s);
    return s;
  }
};

}  // namespace vdmap::test
