#pragma once
// The depth sensor model of synthetic sequences: metric depth from the renderer -> the 16-bit
// depth image a Kinect-like sensor would deliver.
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "mapping/local_map/sensor_model.h"  // nguyenAxialSd

namespace vdmap {

enum class DepthNoiseModel {
  kNone,        ///< exact depth, quantised to the depth scale; only the range limit applies
  kNguyen2012,  ///< Kinect v1 (docs/method.md 3): axial sd(d), lateral jitter, range and angle cuts
};

/// Parses "none" or "nguyen2012" (throws std::invalid_argument otherwise).
DepthNoiseModel parseDepthNoiseModel(const std::string& name);

struct DepthNoiseParams {
  DepthNoiseModel model = DepthNoiseModel::kNguyen2012;
  /// Range of the simulated sensor, metres. Nguyen et al. fit their model on 0.4 - 3+ m; a Kinect
  /// v1 returns little beyond ~5 m. With model kNone only max_range_m applies (and the 16-bit
  /// limit of the depth scale).
  double min_range_m = 0.4;
  double max_range_m = 5.0;
  /// No return where the viewing ray meets the surface at more than this angle from its normal.
  double max_incidence_deg = 80.0;
  /// Lateral noise: each pixel reads the depth of a pixel displaced by N(0, sd) in u and v
  /// (rounded), which frays depth edges like a structured-light sensor; the sensor model's su = sv = 0.8 px (docs/method.md 3).
  double lateral_sd_px = 0.8;
  /// Base of the per-frame seed: frame i uses seed ^ hash(i), so frames are reproducible.
  std::uint64_t seed = 0x76646d6170ull;
};

/// Simulates a depth image. `z_cos` is CV_32FC2: camera z in metres (0 = no surface) and the
/// |cosine| of the incidence angle. Returns CV_16UC1 with metres * depth_scale, rounded; 0 where
/// the sensor returns nothing. Deterministic for a given (params.seed, frame_index).
cv::Mat simulateDepth(const cv::Mat& z_cos, double depth_scale, const DepthNoiseParams& params, int frame_index);

}  // namespace vdmap
