// Cell statistics: the incremental (Chan) merge of docs/method.md 2 equals the batch statistics.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/local_map/cell_stats.h"
#include "mapping/local_map/keyframe_container.h"

namespace vdmap {
namespace {

// docs/method.md 2: the merge must equal batch statistics to 1e-9 relative in double.
// Chan's update is backward stable; with <= 40 batches of <= 50 points the rounding error is a
// few hundred ulps (~1e-13), so 1e-9 leaves margin without hiding a wrong formula (a missing
// M N / (M + N) term is off by O(1)).
constexpr double kRelTol = 1e-9;

double relErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(b.norm(), 1e-300);
}

struct Truth {
  Eigen::Vector3d mean, color;
  Eigen::Matrix3d scatter;
};

Truth batchTruth(const std::vector<Eigen::Vector3d>& pts, const std::vector<Eigen::Vector3d>& cols) {
  Truth t{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()};
  for (const auto& p : pts) t.mean += p;
  t.mean /= pts.size();
  for (const auto& c : cols) t.color += c;
  t.color /= cols.size();
  for (const auto& p : pts) t.scatter += (p - t.mean) * (p - t.mean).transpose();
  return t;
}

TEST(CellStats, IncrementalMergeEqualsBatchStatistics) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 200; ++trial) {
    // A cell-sized cloud (cm spread, anisotropic) far from the origin, as in a local map.
    std::normal_distribution<double> centre(0.0, 3.0), spread(0.0, 1.0);
    std::uniform_int_distribution<int> batch_size(1, 50), batches(1, 40), byte(0, 255);
    const Eigen::Vector3d c0(centre(rng), centre(rng), 0.5 + std::abs(centre(rng)));
    const Eigen::Vector3d axes(0.01, 0.004, 0.0015);
    CellStats cell;
    std::vector<Eigen::Vector3d> all_p, all_c;
    const int nb = batches(rng);
    for (int b = 0; b < nb; ++b) {
      std::vector<Eigen::Vector3d> pts, cols;
      for (int i = batch_size(rng); i > 0; --i) {
        pts.push_back(c0 + Eigen::Vector3d(spread(rng), spread(rng), spread(rng)).cwiseProduct(axes));
        cols.push_back(Eigen::Vector3d(byte(rng), byte(rng), byte(rng)));
      }
      mergeBatch(makeBatch(pts, cols), &cell);
      all_p.insert(all_p.end(), pts.begin(), pts.end());
      all_c.insert(all_c.end(), cols.begin(), cols.end());
    }
    const Truth truth = batchTruth(all_p, all_c);
    ASSERT_EQ(cell.n, static_cast<double>(all_p.size()));
    EXPECT_LT(relErr(cell.mean, truth.mean), kRelTol) << "trial " << trial;
    EXPECT_LT(relErr(cell.scatter, truth.scatter), kRelTol) << "trial " << trial;
    EXPECT_LT(relErr(cell.covariance(), truth.scatter / (all_p.size() - 1.0)), kRelTol);
    EXPECT_LT(relErr(cell.color, truth.color), kRelTol) << "trial " << trial;
  }
}

TEST(CellStats, SinglePointsOneAtATimeEqualBatch) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  CellStats cell;
  std::vector<Eigen::Vector3d> pts, cols;
  for (int i = 0; i < 1000; ++i) {
    pts.push_back(Eigen::Vector3d(1 + 0.01 * g(rng), -2 + 0.02 * g(rng), 4 + 0.003 * g(rng)));
    cols.push_back(Eigen::Vector3d(100 + g(rng), 50, 20));
    mergeBatch(makeBatch(std::vector<Eigen::Vector3d>{pts.back()}, std::vector<Eigen::Vector3d>{cols.back()}), &cell);
  }
  const Truth truth = batchTruth(pts, cols);
  EXPECT_LT(relErr(cell.mean, truth.mean), kRelTol);
  EXPECT_LT(relErr(cell.scatter, truth.scatter), kRelTol);
  EXPECT_LT(relErr(cell.color, truth.color), kRelTol);
}

TEST(CellStats, EmptyBatchIsANoOpAndTooFewPointsHaveNoCovariance) {
  CellStats cell;
  mergeBatch(PointBatch{}, &cell);
  EXPECT_EQ(cell.n, 0.0);
  mergeBatch(makeBatch(std::vector<Eigen::Vector3d>{{1, 2, 3}}, std::vector<Eigen::Vector3d>{{9, 9, 9}}), &cell);
  EXPECT_EQ(cell.n, 1.0);
  EXPECT_EQ(cell.mean, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(cell.covariance().isZero());
}

TEST(CellStats, StoredCellRoundTripsInFloatAndFitsIn64Bytes) {
  static_assert(sizeof(StoredCell) <= 64);
  CellStats s;
  s.n = 17;
  s.mean = {1.25, -0.5, 3.0};
  s.scatter << 2e-4, 1e-5, -3e-6, 1e-5, 5e-5, 2e-6, -3e-6, 2e-6, 1e-6;
  s.color = {10.5, 200.25, 33};
  StoredCell c;
  c.fromStats(s);
  const CellStats back = c.toStats();
  // float has a 24-bit mantissa: 6e-8 relative per value.
  EXPECT_LT(relErr(back.mean, s.mean), 1e-7);
  EXPECT_LT(relErr(back.scatter, s.scatter), 1e-7);
  EXPECT_EQ(back.n, 17.0);
}

}  // namespace
}  // namespace vdmap
