#pragma once
// Small pieces the stages of buildGlobalMap share (docs/method.md 6-7): the covariance floor,
// lambda_max, and a stable counting sort of indices by key.
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap::global_map_detail {

/// Added to every covariance before it is inverted (m^2, a 10 um standard deviation): a flat
/// surface cell has a near-zero axis and must stay invertible; real cells are far wider.
inline constexpr double kCovFloor_m2 = 1e-10;

/// `cov` with kCovFloor_m2 added to its diagonal.
inline Eigen::Matrix3d floored(const Eigen::Matrix3d& cov) { return cov + kCovFloor_m2 * Eigen::Matrix3d::Identity(); }

/// Largest eigenvalue of every ellipsoid's floored covariance, m^2 (occlusion removal and fusion
/// both rank by it), on `threads` threads (0: all).
std::vector<double> largestEigenvalues(const std::vector<Ellipsoid>& ellipsoids, int threads);

/// The address of every ellipsoid of `ellipsoids`, in order: the stages read their input through
/// such a list, so the build can hand them ellipsoids spread over its groups' vectors.
std::vector<const Ellipsoid*> addressesOf(const std::vector<Ellipsoid>& ellipsoids);

/// Empties `v` and gives its memory back (clear() keeps the capacity).
template <typename T>
void releaseVector(std::vector<T>* v) {
  std::vector<T>().swap(*v);
}

/// Indices 0..keys.size()-1 grouped by key (a stable counting sort); negative keys are left out.
/// Bucket b holds order[start[b] .. start[b + 1]).
struct Buckets {
  std::vector<int> start;
  std::vector<int> order;
};

/// Fills `b` with `keys` grouped into `buckets` buckets, reusing its memory (`fill` is scratch).
void bucketByKey(const std::vector<int>& keys, std::size_t buckets, Buckets* b, std::vector<int>* fill);

}  // namespace vdmap::global_map_detail
