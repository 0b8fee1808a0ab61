// The NDT-OM baseline (app/bench/ndt_om_baseline.h): its cells equal the batch statistics of every point
// ever assigned to them, as the local map's do (docs/method.md 2).
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "app/bench/ndt_om_baseline.h"
#include "tests/support/local_map_oracle.h"

namespace vdmap {
namespace {

TEST(NdtOm, CellsEqualBatchStatisticsOfAllTheirPoints) {
  const PinholeCamera cam = test::sceneCamera();
  const auto scene = test::boxScene({-0.3, -0.2, 1.2}, {0.3, 0.2, 1.6});
  NdtOmParams params;
  params.resolution_m = 0.05;
  NdtOmBaseline map(params);
  // Reference: every world point kept, grouped by the cell index computed independently.
  std::map<std::array<long, 3>, std::vector<Eigen::Vector3d>> points, colors;
  for (int i = 0; i < 4; ++i) {
    const Transform T = test::lookAt({0.5 - 0.2 * i, -0.4, 0.1 * i}, {0, 0, 1.4});
    const RgbdFrame f = test::renderFrame(
        scene, cam, T, [](double) { return 0.002; }, 10 + i);
    map.integrateFrame(f, cam);
    // The baseline's documented input: toPointCloud, moved to the world frame in float.
    const ColoredPointCloud cloud = toPointCloud(f, cam, params.depth_range);
    for (std::size_t k = 0; k < cloud.size(); ++k) {
      const Eigen::Vector3d p = (f.T_W_C.cast<float>() * cloud.points[k]).cast<double>();
      const std::array<long, 3> cell = {std::lround(std::floor(p.x() / 0.05)), std::lround(std::floor(p.y() / 0.05)),
                                        std::lround(std::floor(p.z() / 0.05))};
      points[cell].push_back(p);
      colors[cell].push_back(Eigen::Vector3d(cloud.colors[k][0], cloud.colors[k][1], cloud.colors[k][2]));
    }
  }
  ASSERT_GT(map.size(), 100u);
  ASSERT_EQ(map.size(), points.size());
  // means() is in key order, which packs x, y, z of the cell index from the high bits down:
  // the lexicographic order of `points`.
  const std::vector<Eigen::Vector3f> means = map.means();
  ASSERT_EQ(means.size(), points.size());
  std::size_t i = 0;
  for (const auto& [cell, pts] : points) {
    CellStats expected;
    mergeBatch(makeBatch(pts, colors.at(cell)), &expected);
    // float output: 1.2e-7 relative of coordinates below 2 m.
    EXPECT_LT((means[i++].cast<double>() - expected.mean).norm(), 1e-6) << "cell " << i - 1;
    const auto it = map.cells().find(map.keyOf(pts.front()));
    ASSERT_NE(it, map.cells().end());
    const CellStats& got = it->second;
    ASSERT_EQ(got.n, expected.n);
    // 1e-9 relative (docs/method.md 2), on coordinates of ~1.5 m and spreads of ~1 cm.
    EXPECT_LT((got.mean - expected.mean).norm(), 1e-9 * 2.0);
    EXPECT_LT((got.covariance() - expected.covariance()).norm(), 1e-9 * std::max(1e-4, expected.covariance().norm()));
    EXPECT_LT((got.color - expected.color).norm(), 1e-9 * 255);
  }
}

TEST(NdtOm, RejectsBadResolution) {
  for (const double bad : {0.0, -0.1, std::nan("")}) {
    NdtOmParams params;
    params.resolution_m = bad;
    EXPECT_THROW(NdtOmBaseline{params}, std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace vdmap
