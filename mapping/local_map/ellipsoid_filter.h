#pragma once
// Ellipsoid filtering (docs/method.md 4) as a view over a container: nothing is deleted, so the
// thresholds can change live and be undone.

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "mapping/core/types.h"
#include "mapping/local_map/keyframe_container.h"
#include "mapping/local_map/sensor_model.h"

namespace vdmap {

/// Live parameters of the filter (docs/parameters.md).
struct FilterParams {
  SensorModel model = SensorModel::kNguyen2012;
  double filter_sigma_factor = 3.0;  ///< k
  int min_points = 6;
  bool operator==(const FilterParams&) const = default;
};

/// One ellipsoid as the global map, exports and the renderer see it.
struct Ellipsoid {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();   ///< metres, in the frame asked for
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();    ///< Sigma = S / (n - 1), m^2
  Eigen::Vector3f color = Eigen::Vector3f::Zero();  ///< mean RGB, 0..255
  std::uint32_t count = 0;                          ///< points merged into it
  int keyframe = -1;                                ///< id of the keyframe it belongs to
  int grid_index = -1;                              ///< its cell in that keyframe's container
};

/// The largest eigenvalue of a symmetric 3x3 matrix (closed form).
double largestEigenvalue(const Eigen::Matrix3d& m);

/// True when `cell` passes the filter: n >= min_points, its mean lies in front of the keyframe,
/// and sqrt(lambda_max(Sigma)) <= k sqrt(lambda_max(Sigma_expected)), where Sigma_expected is
/// the sensor model's covariance at the pixel and depth the mean projects to, with the cell
/// footprint s^2/12 added (docs/method.md 3-4).
bool keepCell(const StoredCell& cell, const KeyframeContainer& container, const FilterParams& filter);

/// keepCell for every cell of `container`, in container order.
std::vector<bool> keptCells(const KeyframeContainer& container, const FilterParams& filter);

/// A stored cell as an ellipsoid with mean and covariance moved into the frame of T_X_K.
Ellipsoid cellEllipsoid(const StoredCell& cell, const Transform& T_X_K, int keyframe_id);

/// Calls `visit` for every cell of `container` whose `kept` entry is set (keptCells' answer), as an
/// ellipsoid with mean and covariance moved into the frame of T_X_K (Identity: keyframe frame;
/// T_W_K: world), in container order.
void forEachKeptEllipsoid(const KeyframeContainer& container, const std::vector<bool>& kept, const Transform& T_X_K,
                          int keyframe_id, const std::function<void(const Ellipsoid&)>& visit);

/// The kept ellipsoids of a container in the frame of T_X_K (keptCells, then forEachKeptEllipsoid).
std::vector<Ellipsoid> keptEllipsoids(const KeyframeContainer& container, const FilterParams& filter,
                                      const Transform& T_X_K, int keyframe_id);

}  // namespace vdmap
