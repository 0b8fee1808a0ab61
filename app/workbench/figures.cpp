#include "app/workbench/figures.h"

#include <mutex>
#include <vector>

#include "mapping/eval/trajectory_error.h"

namespace vdmap::app::gui {
namespace {

bool samePoses(const std::vector<StampedPose>& a, const std::vector<StampedPose>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].t != b[i].t || a[i].T_W_C.matrix() != b[i].T_W_C.matrix()) return false;
  return true;
}

}  // namespace

TrackingError trackingError(const MappingSnapshot& mapping) {
  std::vector<StampedPose> estimate, truth;
  if (mapping.mapper.poses == PoseSource::kTrack) {
    for (std::size_t i = 0; i < mapping.trajectory.size(); ++i) {
      const TrajectoryPoint& f = mapping.trajectory[i];
      if (!f.T_W_C_truth) continue;
      estimate.push_back({f.t, mapping.framePose(i)});
      truth.push_back({f.t, *f.T_W_C_truth});
    }
  }
  if (estimate.size() < 3) return {};
  // One evaluation per set of inputs: a new mapping generation either changes them (a frame, a
  // keyframe pose) or gives the same figures.
  static std::mutex mutex;
  static std::vector<StampedPose> cached_estimate, cached_truth;
  static TrackingError cached;
  std::lock_guard lock(mutex);
  if (samePoses(estimate, cached_estimate) && samePoses(truth, cached_truth)) return cached;
  TrackingError out;
  try {
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    out.valid = true;
    out.matched = e.matched;
    out.ate_rmse_m = e.ate_m.rmse;
    out.ate_median_m = e.ate_m.median;
    out.ate_max_m = e.ate_m.max;
    out.rpe_frame_m = e.rpe_per_frame.translation_m.rmse;
    out.rpe_frame_deg = e.rpe_per_frame.rotation_deg.rmse;
    out.rpe_second_m = e.rpe_per_second.translation_m.rmse;
    out.rpe_second_deg = e.rpe_per_second.rotation_deg.rmse;
    out.rpe_second_pairs = e.rpe_per_second.translation_m.count;
  } catch (const std::invalid_argument&) {
    // Timestamps that do not increase (a saved session's frames have none): no figures.
  }
  cached_estimate = std::move(estimate);
  cached_truth = std::move(truth);
  cached = out;
  return out;
}

}  // namespace vdmap::app::gui
