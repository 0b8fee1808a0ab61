// The sorted voxel grid of fusion across groups (docs/method.md 7): keys, binning, and the walk
// over a voxel and its forward neighbours, against a brute-force oracle over every pair of points.
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/global_map/sorted_voxel_grid.h"

namespace vdmap {
namespace {

TEST(VoxelKey, PacksAndUnpacksEachAxisAndSortsLikeXYZ) {
  const std::int64_t max = VoxelKey::kAxisMax;
  for (const auto& [x, y, z] :
       std::vector<std::array<std::int64_t, 3>>{{0, 0, 0}, {1, 2, 3}, {max, 0, max}, {max, max, max}}) {
    const std::uint64_t key = VoxelKey::pack(x, y, z);
    EXPECT_EQ(VoxelKey::x(key), x);
    EXPECT_EQ(VoxelKey::y(key), y);
    EXPECT_EQ(VoxelKey::z(key), z);
  }
  EXPECT_LT(VoxelKey::pack(0, max, max), VoxelKey::pack(1, 0, 0));
  EXPECT_LT(VoxelKey::pack(3, 0, max), VoxelKey::pack(3, 1, 0));
  EXPECT_LT(VoxelKey::pack(3, 4, 5), VoxelKey::pack(3, 4, 6));
}

// Random points in a 1 m box, some repeated, binned at 0.1 m.
std::vector<Eigen::Vector3d> randomPoints(std::size_t n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < n; ++i) points.emplace_back(u(rng), u(rng), 0.2 * u(rng));
  for (std::size_t i = 0; i < n / 10; ++i) points.push_back(points[3 * i]);
  return points;
}

TEST(SortedVoxelGrid, MeetsEveryPairOfPointsInAdjacentVoxelsOnce) {
  const std::vector<Eigen::Vector3d> points = randomPoints(2000);
  const double side = 0.1;
  SortedVoxelGrid grid;
  grid.build(
      points.size(), [&](std::size_t i) -> const Eigen::Vector3d& { return points[i]; }, side, 1);

  // The oracle: the voxel of each point counted from the points' lower corner, and every pair
  // whose voxels differ by at most one along each axis.
  Eigen::Vector3d lo = points[0];
  for (const Eigen::Vector3d& p : points) lo = lo.cwiseMin(p);
  auto voxelOf = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(((p - lo) / side).array().floor()); };
  std::set<std::pair<int, int>> expected;
  for (std::size_t a = 0; a < points.size(); ++a)
    for (std::size_t b = a + 1; b < points.size(); ++b)
      if ((voxelOf(points[a]) - voxelOf(points[b])).cwiseAbs().maxCoeff() <= 1.0)
        expected.insert({static_cast<int>(a), static_cast<int>(b)});

  std::multiset<std::pair<int, int>> met;
  std::size_t binned = 0;
  for (std::size_t v = 0; v < grid.voxelCount(); ++v) {
    for (std::size_t k = grid.voxelBegin(v); k < grid.voxelEnd(v); ++k) {
      ++binned;
      EXPECT_EQ(voxelOf(points[static_cast<std::size_t>(grid.pointAt(k))]),
                voxelOf(points[static_cast<std::size_t>(grid.pointAt(grid.voxelBegin(v)))]));
      if (k > grid.voxelBegin(v)) {
        EXPECT_LT(grid.pointAt(k - 1), grid.pointAt(k));  // ascending index
      }
    }
    for (int o = -1; o < SortedVoxelGrid::kForwardNeighbours; ++o) {
      const int u = o < 0 ? static_cast<int>(v) : grid.forwardNeighbour(v, static_cast<std::size_t>(o));
      if (u < 0) continue;
      for (std::size_t k = grid.voxelBegin(v); k < grid.voxelEnd(v); ++k)
        for (std::size_t l = o < 0 ? k + 1 : grid.voxelBegin(static_cast<std::size_t>(u));
             l < grid.voxelEnd(static_cast<std::size_t>(u)); ++l)
          met.insert(std::minmax(grid.pointAt(k), grid.pointAt(l)));
    }
  }
  EXPECT_EQ(binned, points.size());
  EXPECT_EQ(met.size(), expected.size());  // a multiset: a pair met twice would count twice
  const std::set<std::pair<int, int>> distinct(met.begin(), met.end());
  EXPECT_EQ(distinct, expected);
}

TEST(SortedVoxelGrid, IsTheSameForAnyThreadCountAndReusedMemory) {
  const std::vector<Eigen::Vector3d> points = randomPoints(5000);
  auto point = [&](std::size_t i) -> const Eigen::Vector3d& { return points[i]; };
  SortedVoxelGrid one, two;
  two.build(10, point, 0.3, 2);  // a smaller grid first: its memory is reused
  one.build(points.size(), point, 0.05, 1);
  two.build(points.size(), point, 0.05, 2);
  ASSERT_EQ(one.voxelCount(), two.voxelCount());
  for (std::size_t v = 0; v < one.voxelCount(); ++v) {
    ASSERT_EQ(one.voxelBegin(v), two.voxelBegin(v));
    for (std::size_t o = 0; o < SortedVoxelGrid::kForwardNeighbours; ++o)
      ASSERT_EQ(one.forwardNeighbour(v, o), two.forwardNeighbour(v, o));
  }
  for (std::size_t k = 0; k < points.size(); ++k) ASSERT_EQ(one.pointAt(k), two.pointAt(k));
}

TEST(SortedVoxelGrid, WidensVoxelsThatAKeyCannotCount) {
  // 100 km apart at 1 mm voxels would need 10^8 voxels along x: the voxels grow instead, and the
  // two points still fall into different voxels that are not neighbours.
  const std::vector<Eigen::Vector3d> points = {{0, 0, 0}, {1e5, 0, 0}, {1e5, 1e-3, 0}};
  SortedVoxelGrid grid;
  grid.build(
      points.size(), [&](std::size_t i) -> const Eigen::Vector3d& { return points[i]; }, 1e-3, 1);
  ASSERT_EQ(grid.voxelCount(), 2u);
  EXPECT_EQ(grid.voxelEnd(0) - grid.voxelBegin(0), 1u);
  EXPECT_EQ(grid.voxelEnd(1) - grid.voxelBegin(1), 2u);
  for (std::size_t o = 0; o < SortedVoxelGrid::kForwardNeighbours; ++o) EXPECT_EQ(grid.forwardNeighbour(0, o), -1);
}

}  // namespace
}  // namespace vdmap
