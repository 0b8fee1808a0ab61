// Trajectory error (mapping/eval/trajectory_error): timestamp association as associate.py, ATE
// after the rigid alignment, RPE per frame and per second, on trajectories with known answers.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/core/error.h"
#include "mapping/eval/trajectory_error.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

constexpr double kDegree = M_PI / 180.0;

Transform pose(const Eigen::Vector3d& p, double yaw, double pitch = 0.0) {
  Transform T = Transform::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = p;
  return T;
}

/// 10 s at 30 Hz on a circle of radius `radius_m` in the z = 1 plane (one turn), facing along it.
std::vector<StampedPose> circle(double radius_m = 2.0, int frames = 300) {
  std::vector<StampedPose> poses;
  for (int i = 0; i < frames; ++i) {
    const double a = 2.0 * M_PI * i / frames;
    poses.push_back({100.0 + i / 30.0,
                     pose({radius_m * std::cos(a), radius_m * std::sin(a), 1.0}, a + M_PI / 2, 0.1 * std::sin(3 * a))});
  }
  return poses;
}

std::vector<StampedPose> moved(std::vector<StampedPose> poses, const Transform& T) {
  for (StampedPose& p : poses) p.T_W_C = T * p.T_W_C;
  return poses;
}

TEST(TrajectoryError, ARigidlyMovedCopyHasNoError) {
  const std::vector<StampedPose> gt = circle();
  const std::vector<StampedPose> est = moved(gt, pose({3.0, -1.0, 0.5}, 40 * kDegree, 20 * kDegree));
  const TrajectoryError e = evaluateTrajectory(est, gt);
  EXPECT_EQ(e.matched, gt.size());
  EXPECT_LT(e.ate_m.rmse, 1e-9);
  EXPECT_LT(e.ate_m.max, 1e-9);
  EXPECT_EQ(e.rpe_per_frame.translation_m.count, gt.size() - 1);
  EXPECT_LT(e.rpe_per_frame.translation_m.max, 1e-9);
  EXPECT_LT(e.rpe_per_frame.rotation_deg.max, 1e-6);
  EXPECT_GT(e.rpe_per_second.translation_m.count, 200u);
  EXPECT_LT(e.rpe_per_second.translation_m.max, 1e-9);
  // The alignment found is the inverse of the motion applied.
  const Transform expected = pose({3.0, -1.0, 0.5}, 40 * kDegree, 20 * kDegree).inverse();
  EXPECT_TRUE(e.T_gt_est.isApprox(expected, 1e-9));
  EXPECT_EQ(e.scale, 1.0);
}

// A circle of radius R + d against one of radius R: no rigid motion changes a radius, and by
// symmetry the best one is the identity, so every pose is off by exactly d.
TEST(TrajectoryError, AKnownOffsetIsTheError) {
  const std::vector<StampedPose> gt = circle(2.0);
  std::vector<StampedPose> est = circle(2.05);
  const TrajectoryError e = evaluateTrajectory(moved(est, pose({1, 2, 3}, 1.0)), gt);
  EXPECT_NEAR(e.ate_m.rmse, 0.05, 1e-9);
  EXPECT_NEAR(e.ate_m.mean, 0.05, 1e-9);
  EXPECT_NEAR(e.ate_m.median, 0.05, 1e-9);
  EXPECT_NEAR(e.ate_m.max, 0.05, 1e-9);
  // With a scale in the alignment the bigger circle fits exactly, at scale 2 / 2.05.
  TrajectoryErrorParams sim3;
  sim3.align_scale = true;
  const TrajectoryError s = evaluateTrajectory(est, gt, sim3);
  EXPECT_NEAR(s.scale, 2.0 / 2.05, 1e-9);
  EXPECT_LT(s.ate_m.rmse, 1e-9);
}

// Pose k of a straight walk (1 m/s along x, 30 Hz) displaced by 3 cm: the two per-frame pairs
// that contain it are off by 3 cm, all others by 0. Pose m turned by 2 degrees in place: the
// two pairs that contain it are off by 2 degrees.
TEST(TrajectoryError, RelativePoseErrorOfKnownPerturbations) {
  std::vector<StampedPose> gt;
  for (int i = 0; i < 90; ++i) gt.push_back({i / 30.0, pose({i / 30.0, 0.0, 0.0}, 0.0)});
  std::vector<StampedPose> est = gt;
  est[20].T_W_C.translation().y() += 0.03;
  est[60].T_W_C.linear() =
      est[60].T_W_C.linear() * Eigen::AngleAxisd(2 * kDegree, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const TrajectoryError e = evaluateTrajectory(est, gt);
  const ErrorStats& t = e.rpe_per_frame.translation_m;
  const ErrorStats& r = e.rpe_per_frame.rotation_deg;
  EXPECT_EQ(t.count, 89u);
  EXPECT_NEAR(t.max, 0.03, 1e-12);
  // Pairs (19, 20) and (20, 21) are off by 3 cm; (60, 61) by the turned step 1/30 m * 2 sin(1 deg).
  const double turned_step = 2.0 * std::sin(1 * kDegree) / 30.0;
  EXPECT_NEAR(t.rmse, std::sqrt((2 * 0.03 * 0.03 + turned_step * turned_step) / 89), 1e-12);
  EXPECT_NEAR(r.max, 2.0, 1e-9);
  EXPECT_NEAR(r.rmse, std::sqrt(2 * 4.0 / 89), 1e-9);
  EXPECT_EQ(r.median, 0.0);

  // A 10 % scale drift: the estimate walks 1.1 m per metre, so every 1 s pair is off by 0.1 m,
  // every frame pair by 0.1/30 m.
  std::vector<StampedPose> fast = gt;
  for (StampedPose& p : fast) p.T_W_C.translation() *= 1.1;
  const TrajectoryError d = evaluateTrajectory(fast, gt);
  EXPECT_EQ(d.rpe_per_second.translation_m.count, 60u) << "pairs i, i+30 for i = 0..59";
  EXPECT_NEAR(d.rpe_per_second.translation_m.rmse, 0.1, 1e-9);
  EXPECT_NEAR(d.rpe_per_second.translation_m.max, 0.1, 1e-9);
  EXPECT_NEAR(d.rpe_per_frame.translation_m.mean, 0.1 / 30, 1e-9);
}

StampedPose at(double t) { return {t, Transform::Identity()}; }

// associate.py's rules: strictly within the maximum difference, one-to-one, greedy by the
// smallest difference, the offset added to the estimate's timestamps.
TEST(TrajectoryError, AssociationIsOneToOneAndGreedy) {
  using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;
  const std::vector<StampedPose> est = {at(1.000), at(1.010), at(2.000), at(3.000)};
  const std::vector<StampedPose> gt = {at(1.008), at(2.019), at(2.9), at(3.0199)};
  // 1.010 is closer to 1.008 than 1.000 is, so it takes it and 1.000 stays unmatched; 2.000 is
  // 0.019 from 2.019 (< 0.02); 3.0 is 0.0199 from 3.0199.
  EXPECT_EQ(associateTimestamps(est, gt), (Pairs{{1, 0}, {2, 1}, {3, 3}}));
  TrajectoryErrorParams tight;
  tight.max_difference_s = 0.019;
  EXPECT_EQ(associateTimestamps(est, gt, tight), (Pairs{{1, 0}}));
  TrajectoryErrorParams shifted;
  shifted.offset_s = -0.1;  // est + offset: 0.9, 0.91, 1.9, 2.9
  EXPECT_EQ(associateTimestamps(est, gt, shifted), (Pairs{{3, 2}}));
  // A tie goes to the earlier ground-truth timestamp (the script sorts (difference, t_gt, t_est)).
  // (5 -+ 1/128 are exact in binary, so the differences are equal.)
  const std::vector<StampedPose> one = {at(5.0)};
  const std::vector<StampedPose> two = {at(5.0 - 1.0 / 128), at(5.0 + 1.0 / 128)};
  EXPECT_EQ(associateTimestamps(one, two), (Pairs{{0, 0}}));
}

// An estimate at other timestamps (a 30 Hz estimate against 100 Hz ground truth shifted by a
// known time offset) is scored on the associated poses only.
TEST(TrajectoryError, OffsetAlignsTimestamps) {
  std::vector<StampedPose> gt;  // a path no rigid motion maps onto a shifted part of itself
  for (int i = 0; i < 1000; ++i) {
    const double s = i / 100.0;
    gt.push_back({100.0 + s, pose({0.3 * s, std::sin(1.3 * s), 0.05 * s * s}, 0.2 * s)});
  }
  std::vector<StampedPose> est;
  for (std::size_t i = 0; i < gt.size(); i += 3) est.push_back({gt[i].t + 7.0, gt[i].T_W_C});
  // Without the offset the last 3 s of ground truth pair with the estimate's first 3 s: wrong poses.
  EXPECT_GT(evaluateTrajectory(est, gt).ate_m.rmse, 0.2);
  TrajectoryErrorParams params;
  params.offset_s = -7.0;
  const TrajectoryError e = evaluateTrajectory(est, gt, params);
  EXPECT_EQ(e.matched, est.size());
  EXPECT_LT(e.ate_m.rmse, 1e-9);
}

TEST(TrajectoryError, RefusesTooFewMatchesAndBadParameters) {
  const std::vector<StampedPose> gt = circle();
  const std::vector<StampedPose> two(gt.begin(), gt.begin() + 2);
  try {
    evaluateTrajectory(two, gt);
    ADD_FAILURE() << "accepted two poses";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "2 of 2 poses match a ground-truth timestamp within 0.02 s; at least 3 are needed for the alignment");
  }
  TrajectoryErrorParams p;
  p.max_difference_s = 0.0;
  EXPECT_THROW(evaluateTrajectory(gt, gt, p), std::invalid_argument);
  p = {};
  p.rpe_delta_s = NAN;
  EXPECT_THROW(evaluateTrajectory(gt, gt, p), std::invalid_argument);
  std::vector<StampedPose> backwards = gt;
  std::swap(backwards[3], backwards[4]);
  EXPECT_THROW(evaluateTrajectory(backwards, gt), std::invalid_argument);
  std::vector<StampedPose> still = gt;
  for (StampedPose& s : still) s.T_W_C.translation().setZero();
  p = {};
  p.align_scale = true;
  EXPECT_THROW(evaluateTrajectory(still, gt, p), std::invalid_argument);
}

// `vdmap eval --trajectory` prints the figures, as JSON with --json (rounded as stats.json's).
TEST(TrajectoryError, EvalCommand) {
  test::TempDir dir;
  const std::vector<StampedPose> gt = circle(2.0);
  writeTumTrajectory(dir / "gt.txt", gt, "ground truth");
  writeTumTrajectory(dir / "est.txt", circle(2.05), "estimate");
  const auto r = test::runVdmap("eval --trajectory '" + (dir / "est.txt").string() + "' --groundtruth '" +
                                (dir / "gt.txt").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::size_t at = r.out.find("\"ate_rmse_m\": ");
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_NEAR(std::stod(r.out.substr(at + 14)), 0.05, 1e-6) << r.out;
  EXPECT_EQ(r.out.substr(at + 14, 5), "0.05,") << r.out;  // 5 significant digits, as stats.json's figures
  EXPECT_NE(r.out.find("\"matched\": 300"), std::string::npos) << r.out;
  const auto text = test::runVdmap("eval --trajectory '" + (dir / "est.txt").string() + "' --groundtruth '" +
                                   (dir / "gt.txt").string() + "'");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("ATE"), std::string::npos) << text.out;
}

}  // namespace
}  // namespace vdmap
