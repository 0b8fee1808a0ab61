#pragma once
// Fusion across groups (docs/method.md 7), the last stage of buildGlobalMap, after occlusion
// removal (6.3). Its public pieces (bhattacharyyaDistance, fusionHalfWidth, fuseAcrossGroups over
// a vector) are declared in global_map.h.
#include <span>
#include <utility>
#include <vector>

#include "mapping/global_map/detail/global_map_helpers.h"
#include "mapping/global_map/global_map.h"
#include "mapping/global_map/sorted_voxel_grid.h"

namespace vdmap::global_map_detail {

/// A floored covariance as its six distinct entries, with the closed forms the Bhattacharyya
/// distance needs (fusion evaluates it for millions of pairs).
struct SymmetricCov {
  double xx, xy, xz, yy, yz, zz;
  static SymmetricCov of(const Eigen::Matrix3d& cov) {
    return {cov(0, 0) + kCovFloor_m2, cov(0, 1), cov(0, 2),
            cov(1, 1) + kCovFloor_m2, cov(1, 2), cov(2, 2) + kCovFloor_m2};
  }
  SymmetricCov average(const SymmetricCov& o) const {
    return {0.5 * (xx + o.xx), 0.5 * (xy + o.xy), 0.5 * (xz + o.xz),
            0.5 * (yy + o.yy), 0.5 * (yz + o.yz), 0.5 * (zz + o.zz)};
  }
  double determinant() const { return xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz); }
  /// d^T S^-1 d through the adjugate.
  double inverseQuadratic(const Eigen::Vector3d& d) const {
    const double axx = yy * zz - yz * yz, axy = xz * yz - xy * zz, axz = xy * yz - xz * yy;
    const double ayy = xx * zz - xz * xz, ayz = xy * xz - xx * yz, azz = xx * yy - xy * xy;
    const double x = d.x(), y = d.y(), z = d.z();
    return (x * (axx * x + axy * y + axz * z) + y * (axy * x + ayy * y + ayz * z) + z * (axz * x + ayz * y + azz * z)) /
           determinant();
  }
};

/// A match of fusion: ellipsoids a and b are copies of one surface at this distance.
struct FusionMatch {
  int a, b;
  double distance;
};

/// Fusion's buffers, reused across builds. The search reads the ellipsoids in the grid's sorted
/// order (position k: mean, cov, lambda, group and index of the ellipsoid at grid position k).
struct FusionBuffers {
  /// False: each step frees what the later ones no longer read (a build that is not repeated).
  bool keep = true;
  SortedVoxelGrid grid;
  std::vector<Eigen::Vector3d> mean;
  std::vector<SymmetricCov> cov;
  std::vector<double> lambda;
  std::vector<int> group, index;
  std::vector<std::vector<FusionMatch>> found;  ///< per chunk of voxels
  /// Both directions of every match, per ellipsoid: i's partners are partner[partner_start[i] ..
  /// partner_start[i + 1]), as (other ellipsoid, distance).
  std::vector<int> partner_start;
  std::vector<std::pair<int, double>> partner, taken;
  std::vector<std::pair<double, int>> order;
  std::vector<int> fill, seed_of, member_of;
  std::vector<std::size_t> slot;
  Buckets members;
};

/// fuseAcrossGroups (global_map.h) of world-frame ellipsoids, lambda_max[i] being the largest
/// eigenvalue of ellipsoid i's floored covariance, with the given buffers. The same result for
/// any params.threads; one call per `buffers` at a time.
std::vector<Ellipsoid> fuseAcrossGroups(std::span<const Ellipsoid* const> ellipsoids, const std::vector<int>& group_of,
                                        const std::vector<double>& lambda_max, const GlobalMapParams& params,
                                        FusionBuffers* buffers);

}  // namespace vdmap::global_map_detail
