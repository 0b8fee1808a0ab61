#include "mapping/local_map/sensor_model.h"

#include <algorithm>
#include <stdexcept>

namespace vdmap {

SensorModel parseSensorModel(const std::string& name) {
  if (name == "nguyen2012") return SensorModel::kNguyen2012;
  if (name == "belter2018") return SensorModel::kBelter2018;
  throw std::invalid_argument("unknown sensor model '" + name + "' (expected nguyen2012 or belter2018)");
}

const char* sensorModelName(SensorModel model) {
  return model == SensorModel::kNguyen2012 ? "nguyen2012" : "belter2018";
}

PixelVariance pixelVariance(SensorModel model, double d) {
  PixelVariance var;
  if (model == SensorModel::kNguyen2012) {
    const double sd = nguyenAxialSd(d);
    var = {0.8 * 0.8, 0.8 * 0.8, sd * sd};
  } else {
    // The cubic fit goes slightly negative below ~0.03 m; clamp so the covariance stays
    // positive semi-definite (depths that small are outside any valid range anyway).
    const double sd2 = -8.9997e-6 * d * d * d + 3.069e-3 * d * d + 3.6512e-6 * d - 1.7512e-6;
    var = {1.1046, 0.64160, std::max(sd2, 0.0)};
  }
  return var;
}

Eigen::Matrix3d pointCovariance(SensorModel model, const PinholeCamera& camera, double u, double v, double depth_m,
                                double extra_px2) {
  const PixelVariance var = pixelVariance(model, depth_m);
  const Eigen::Matrix3d J = camera.backProjectJacobian(u, v, depth_m);
  const Eigen::Vector3d diag(var.u_px2 + extra_px2, var.v_px2 + extra_px2, var.depth_m2);
  return J * diag.asDiagonal() * J.transpose();
}

}  // namespace vdmap
