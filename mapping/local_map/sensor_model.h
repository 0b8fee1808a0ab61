#pragma once
// Depth-sensor uncertainty models (docs/method.md 3).

#include <string>

#include <Eigen/Core>

#include "mapping/core/camera.h"

namespace vdmap {

enum class SensorModel {
  kNguyen2012,  ///< Kinect v1 per-pixel model (Nguyen, Izadi, Lovell 2012); the default
  kBelter2018,  ///< the authors' feature-point model (PUTSLAM depthSensorModel)
};

/// "nguyen2012" or "belter2018"; throws std::invalid_argument naming the accepted values.
SensorModel parseSensorModel(const std::string& name);
const char* sensorModelName(SensorModel model);

/// Pixel and depth variances of one measurement: u, v in px^2, depth in m^2.
struct PixelVariance {
  double u_px2 = 0.0;
  double v_px2 = 0.0;
  double depth_m2 = 0.0;
};
PixelVariance pixelVariance(SensorModel model, double depth_m);

/// Axial (depth) standard deviation of Nguyen et al. 2012 (docs/method.md 3), metres.
inline double nguyenAxialSd(double depth_m) { return 0.0012 + 0.0019 * (depth_m - 0.4) * (depth_m - 0.4); }

/// Covariance (camera frame, m^2) of the point back-projected from pixel (u, v) at depth d:
/// J diag(su2 + extra_px2, sv2 + extra_px2, sd2(d)) J^T with J = camera.backProjectJacobian.
Eigen::Matrix3d pointCovariance(SensorModel model, const PinholeCamera& camera, double u, double v, double depth_m,
                                double extra_px2 = 0.0);

/// Expected covariance of a cell of `cell_size_px` whose ellipsoid centre projects to (u, v)
/// at depth d in its keyframe: the point covariance with the cell footprint s^2/12 added to
/// both pixel variances (docs/method.md 3).
inline Eigen::Matrix3d expectedCellCovariance(SensorModel model, const PinholeCamera& camera, double u, double v,
                                              double depth_m, int cell_size_px) {
  return pointCovariance(model, camera, u, v, depth_m, static_cast<double>(cell_size_px) * cell_size_px / 12.0);
}

}  // namespace vdmap
