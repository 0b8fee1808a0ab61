#pragma once
// A sparse voxel grid kept as a sorted list rather than a hash table: points binned into cubic
// voxels by a packed integer key (VoxelKey), the occupied voxels in key order, and each voxel's
// occupied neighbours found by walking that order. Its iteration order is the key order whatever
// the thread count or the standard library's hashing, which a deterministic map needs (fusion
// across groups, docs/method.md 7).
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "mapping/core/parallel.h"

namespace vdmap {

/// Integer voxel coordinates, each within 0 .. kAxisMax, packed 21 bits per axis into one 64-bit
/// key that sorts like (x, y, z).
struct VoxelKey {
  static constexpr int kBits = 21;
  static constexpr std::int64_t kAxisMax = (std::int64_t{1} << kBits) - 1;

  static constexpr std::uint64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::uint64_t>(x) << (2 * kBits) | static_cast<std::uint64_t>(y) << kBits |
           static_cast<std::uint64_t>(z);
  }
  static constexpr std::int64_t x(std::uint64_t key) { return static_cast<std::int64_t>(key >> (2 * kBits)); }
  static constexpr std::int64_t y(std::uint64_t key) {
    return static_cast<std::int64_t>(key >> kBits & static_cast<std::uint64_t>(kAxisMax));
  }
  static constexpr std::int64_t z(std::uint64_t key) {
    return static_cast<std::int64_t>(key & static_cast<std::uint64_t>(kAxisMax));
  }
};

/// Points binned into cubic voxels counted from their bounding box's lower corner. Not
/// thread-safe while built; const queries may run on many threads.
class SortedVoxelGrid {
 public:
  /// The neighbours of a voxel that come after it in key order, (dx, dy, dz) with (dz, dy, dx)
  /// positive: visiting a voxel and these meets each pair of adjacent voxels once.
  static constexpr int kForwardNeighbours = 13;

  /// Rebuilds the grid over point(0) .. point(n - 1) (metres, any one frame; `point(i)` returns
  /// an Eigen::Vector3d), reusing its memory. Voxels have side `min_side_m`, or more when the
  /// points span more voxels along an axis than a key holds. The same grid for any `threads`
  /// (0: all).
  template <typename PointAt>
  void build(std::size_t n, const PointAt& point, double min_side_m, int threads);

  /// Empties the grid and gives its memory back.
  void release() { *this = SortedVoxelGrid(); }

  std::size_t voxelCount() const { return voxel_.size(); }
  /// Voxel v's points are those at sorted positions voxelBegin(v) .. voxelEnd(v) - 1; voxels in
  /// key order, points within a voxel in ascending index.
  std::size_t voxelBegin(std::size_t v) const { return voxel_start_[v]; }
  std::size_t voxelEnd(std::size_t v) const { return voxel_start_[v + 1]; }
  /// The index of the point at sorted position k.
  int pointAt(std::size_t k) const { return entries_[k].second; }
  /// The voxel at forward offset o (0 .. kForwardNeighbours - 1) of voxel v; -1 when it holds no point.
  int forwardNeighbour(std::size_t v, std::size_t o) const { return neighbour_[v][o]; }

 private:
  // voxel_, voxel_start_ and neighbour_ from the sorted entries_.
  void findVoxels(int threads);

  std::vector<std::pair<std::uint64_t, int>> entries_;  // (voxel key, point index), sorted
  std::vector<std::uint64_t> voxel_;                    // the occupied voxels' keys, ascending
  std::vector<std::size_t> voxel_start_;                // per voxel, then the number of points
  std::vector<std::array<int, kForwardNeighbours>> neighbour_;
};

template <typename PointAt>
void SortedVoxelGrid::build(std::size_t n, const PointAt& point, double min_side_m, int threads) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) lo = lo.cwiseMin(point(i)), hi = hi.cwiseMax(point(i));
  // A map wider than kAxisVoxels along an axis gets larger voxels: coordinates stay within
  // 0 .. kAxisVoxels (the last for rounding at the far corner), so a neighbour's still fit a key.
  constexpr std::int64_t kAxisVoxels = VoxelKey::kAxisMax - 1;
  const double side =
      n > 0 ? std::max(min_side_m, (hi - lo).maxCoeff() / static_cast<double>(kAxisVoxels - 1)) : min_side_m;
  entries_.resize(n);
  parallelFor(threads, n, [&](std::size_t i) {
    const Eigen::Vector3d c = ((point(i) - lo) / side).array().floor();
    entries_[i] = {VoxelKey::pack(static_cast<std::int64_t>(c.x()), static_cast<std::int64_t>(c.y()),
                                  static_cast<std::int64_t>(c.z())),
                   static_cast<int>(i)};
  });
  parallelSort(threads, entries_.begin(), entries_.end());
  findVoxels(threads);
}

}  // namespace vdmap
