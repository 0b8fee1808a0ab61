#include "mapping/core/types.h"

namespace vdmap {

bool isValidTransform(const Transform& T, double tolerance) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < tolerance && R.determinant() > 0.0;
}

}  // namespace vdmap
