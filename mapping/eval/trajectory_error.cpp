#include "mapping/eval/trajectory_error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <tuple>

#include <Eigen/Geometry>

#include "mapping/core/error.h"

namespace vdmap {
namespace {

void checkStampsIncrease(std::span<const StampedPose> poses, const char* which) {
  for (std::size_t i = 1; i < poses.size(); ++i)
    if (!(poses[i].t > poses[i - 1].t))
      throw std::invalid_argument(std::string("the ") + which + "'s timestamps must increase (pose " +
                                  std::to_string(i) + ")");
}

double rotationDegrees(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI; }

/// RPE over index pairs (a, b) into the matched poses.
RelativePoseError relativePoseError(const std::vector<Transform>& est, const std::vector<Transform>& gt,
                                    const std::vector<std::pair<std::size_t, std::size_t>>& pairs, double scale) {
  std::vector<double> translation, rotation;
  for (const auto& [a, b] : pairs) {
    Transform est_ab = est[a].inverse() * est[b];
    est_ab.translation() *= scale;
    const Transform error = est_ab.inverse() * (gt[a].inverse() * gt[b]);
    translation.push_back(error.translation().norm());
    rotation.push_back(rotationDegrees(error.linear()));
  }
  return {errorStats(translation), errorStats(rotation)};
}

}  // namespace

ErrorStats errorStats(std::vector<double> errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) return s;
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
    s.max = std::max(s.max, e);
  }
  s.mean = sum / errors.size();
  s.rmse = std::sqrt(sum_sq / errors.size());
  const std::size_t mid = errors.size() / 2;
  std::nth_element(errors.begin(), errors.begin() + mid, errors.end());
  s.median = errors[mid];
  if (errors.size() % 2 == 0) s.median = 0.5 * (s.median + *std::max_element(errors.begin(), errors.begin() + mid));
  return s;
}

std::vector<std::pair<std::size_t, std::size_t>> associateTimestamps(std::span<const StampedPose> estimate,
                                                                     std::span<const StampedPose> groundtruth,
                                                                     const TrajectoryErrorParams& params) {
  checkStampsIncrease(estimate, "estimate");
  checkStampsIncrease(groundtruth, "ground truth");
  // Every pair within the window, as (difference, t_gt, t_est) like the script's sort key.
  std::vector<std::tuple<double, double, double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate[i].t + params.offset_s;
    auto it = std::lower_bound(groundtruth.begin(), groundtruth.end(), t - params.max_difference_s,
                               [](const StampedPose& p, double v) { return p.t < v; });
    for (; it != groundtruth.end() && it->t <= t + params.max_difference_s; ++it) {
      const double difference = std::abs(it->t - t);
      if (difference < params.max_difference_s)
        candidates.emplace_back(difference, it->t, estimate[i].t, i, it - groundtruth.begin());
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> est_used(estimate.size(), false), gt_used(groundtruth.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const auto& [difference, t_gt, t_est, i, j] : candidates) {
    if (est_used[i] || gt_used[j]) continue;
    est_used[i] = gt_used[j] = true;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

TrajectoryError evaluateTrajectory(std::span<const StampedPose> estimate, std::span<const StampedPose> groundtruth,
                                   const TrajectoryErrorParams& params) {
  if (!(params.max_difference_s > 0.0) || !std::isfinite(params.max_difference_s))
    throw std::invalid_argument("the maximum timestamp difference must be a positive number of seconds");
  if (!std::isfinite(params.offset_s)) throw std::invalid_argument("the time offset must be a finite number");
  if (!(params.rpe_delta_s > 0.0) || !std::isfinite(params.rpe_delta_s))
    throw std::invalid_argument("the relative pose error's step must be a positive number of seconds");
  const auto matches = associateTimestamps(estimate, groundtruth, params);
  TrajectoryError r;
  r.estimate_poses = estimate.size();
  r.groundtruth_poses = groundtruth.size();
  r.matched = matches.size();
  if (matches.size() < 3) {
    char within[64];
    std::snprintf(within, sizeof within, "%g s", params.max_difference_s);
    throw std::invalid_argument(std::to_string(matches.size()) + " of " + std::to_string(estimate.size()) +
                                " poses match a ground-truth timestamp within " + within +
                                "; at least 3 are needed for the alignment");
  }
  const std::size_t n = matches.size();
  std::vector<Transform> est(n), gt(n);
  Eigen::Matrix3Xd est_p(3, n), gt_p(3, n);
  for (std::size_t k = 0; k < n; ++k) {
    est[k] = estimate[matches[k].first].T_W_C;
    gt[k] = groundtruth[matches[k].second].T_W_C;
    est_p.col(k) = est[k].translation();
    gt_p.col(k) = gt[k].translation();
  }

  if (params.align_scale && (est_p.colwise() - est_p.rowwise().mean()).squaredNorm() == 0.0)
    throw std::invalid_argument("the estimate does not move: no scale can be fitted");
  const Eigen::Matrix4d sim3 = Eigen::umeyama(est_p, gt_p, params.align_scale);
  r.scale = params.align_scale ? sim3.block<3, 1>(0, 0).norm() : 1.0;
  r.T_gt_est.linear() = sim3.topLeftCorner<3, 3>() / r.scale;
  r.T_gt_est.translation() = sim3.topRightCorner<3, 1>();
  std::vector<double> ate(n);
  for (std::size_t k = 0; k < n; ++k)
    ate[k] = (r.scale * (r.T_gt_est.linear() * est_p.col(k)) + r.T_gt_est.translation() - gt_p.col(k)).norm();
  r.ate_m = errorStats(ate);

  std::vector<std::pair<std::size_t, std::size_t>> per_frame, per_second;
  for (std::size_t a = 0; a + 1 < n; ++a) per_frame.emplace_back(a, a + 1);
  const auto time = [&](std::size_t k) { return estimate[matches[k].first].t; };
  for (std::size_t a = 0, b = 0; a < n; ++a) {
    const double target = time(a) + params.rpe_delta_s;
    if (target > time(n - 1)) break;
    // b: the matched pose nearest to target (b only moves forward as a does).
    while (b + 1 < n && std::abs(time(b + 1) - target) <= std::abs(time(b) - target)) ++b;
    if (b > a) per_second.emplace_back(a, b);
  }
  r.rpe_per_frame = relativePoseError(est, gt, per_frame, r.scale);
  r.rpe_per_second = relativePoseError(est, gt, per_second, r.scale);
  return r;
}

TrajectoryError evaluateTrajectoryFiles(const std::filesystem::path& estimate, const std::filesystem::path& groundtruth,
                                        const TrajectoryErrorParams& params) {
  const std::vector<StampedPose> est = readTumTrajectory(estimate);
  const std::vector<StampedPose> gt = readTumTrajectory(groundtruth);
  try {
    return evaluateTrajectory(est, gt, params);
  } catch (const std::invalid_argument& e) {
    throw InputError(estimate.string(), std::string(e.what()) + " (ground truth: " + groundtruth.string() + ")");
  }
}

}  // namespace vdmap
