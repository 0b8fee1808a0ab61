#pragma once
// Trajectory error against ground truth, with the definitions of the TUM RGB-D benchmark tools
// (associate.py, evaluate_ate.py, evaluate_rpe.py; Sturm et al., IROS 2012): timestamp
// association, absolute trajectory error after the optimal rigid alignment, relative pose error.
#include <cstddef>
#include <filesystem>
#include <span>
#include <utility>
#include <vector>

#include "mapping/core/types.h"
#include "mapping/io/trajectory_io.h"

namespace vdmap {

struct TrajectoryErrorParams {
  /// associate.py: an estimated pose and a ground-truth pose match when their timestamps (the
  /// estimate's plus offset_s) differ by less than max_difference_s.
  double max_difference_s = 0.02;
  double offset_s = 0.0;
  /// Also fit a scale in the alignment (Sim(3), for monocular estimates). Off: rigid (SE(3)).
  bool align_scale = false;
  /// Time step of the "per second" relative pose error.
  double rpe_delta_s = 1.0;
};

/// Error statistics of a set of per-pose (or per-pair) errors.
struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
};
ErrorStats errorStats(std::vector<double> errors);

/// Relative pose error over pairs of poses a fixed step apart: translation in metres, rotation in
/// degrees (of E = (est_i^-1 est_j)^-1 (gt_i^-1 gt_j), as evaluate_rpe.py).
struct RelativePoseError {
  ErrorStats translation_m;
  ErrorStats rotation_deg;
};

struct TrajectoryError {
  std::size_t estimate_poses = 0;
  std::size_t groundtruth_poses = 0;
  std::size_t matched = 0;  ///< associated pose pairs every figure below is computed on
  /// Distances |T_gt_est * p_est - p_gt| after the alignment T_gt_est (metres).
  ErrorStats ate_m;
  Transform T_gt_est = Transform::Identity();  ///< the rigid part of the alignment
  double scale = 1.0;                          ///< the alignment's scale (1 unless align_scale)
  RelativePoseError rpe_per_frame;             ///< consecutive matched poses
  RelativePoseError rpe_per_second;            ///< matched poses rpe_delta_s apart
};

/// associate.py: all pairs (i, j) of estimate[i] and groundtruth[j] whose timestamps differ by
/// less than max_difference_s (after adding offset_s to the estimate's), taken greedily by the
/// smallest difference, each pose used at most once; sorted by estimate index. Ties go as in the
/// script (then the earlier ground-truth, then the earlier estimated timestamp).
std::vector<std::pair<std::size_t, std::size_t>> associateTimestamps(std::span<const StampedPose> estimate,
                                                                     std::span<const StampedPose> groundtruth,
                                                                     const TrajectoryErrorParams& params = {});

/// Associates the trajectories, aligns the estimate to the ground truth by Umeyama's method
/// (Horn's closed form, the alignment evaluate_ate.py computes) on the matched positions, and
/// computes the absolute trajectory error and the relative pose error per frame and per second.
///
/// Where this differs from the scripts (both have the same definitions otherwise):
/// - The relative pose error is computed on the associated pairs (one-to-one, within
///   max_difference_s), the same pairs as the ATE; evaluate_rpe.py instead takes the ground-truth
///   pose nearest to each estimated one within two ground-truth intervals.
/// - Every pair (i, j) whose step fits in the trajectory is used; evaluate_rpe.py with
///   --fixed_delta also drops every pair ending at the last pose (how it detects the end).
/// - evaluate_rpe.py samples at most 10000 pairs at random; this uses all of them.
/// A trajectory shorter than rpe_delta_s has no per-second pairs (count 0). Throws
/// std::invalid_argument when fewer than 3 poses associate, when a trajectory's timestamps do not
/// increase, when the parameters are not finite (max_difference_s and rpe_delta_s > 0), or when
/// align_scale is asked of an estimate that does not move.
TrajectoryError evaluateTrajectory(std::span<const StampedPose> estimate, std::span<const StampedPose> groundtruth,
                                   const TrajectoryErrorParams& params = {});

/// evaluateTrajectory on two TUM trajectory files. Throws InputError naming the file: the one
/// that does not read, or the estimate when the two do not associate.
TrajectoryError evaluateTrajectoryFiles(const std::filesystem::path& estimate, const std::filesystem::path& groundtruth,
                                        const TrajectoryErrorParams& params = {});

}  // namespace vdmap
