#pragma once
// Figures the workbench shows about the mapping state, computed from its snapshots.
#include <cstddef>

#include "app/workbench/mapping_worker.h"

namespace vdmap::app::gui {

/// Tracked against true: mapping/eval/trajectory_error.h (the TUM benchmark's definitions) on the
/// snapshot's tracked frame poses (framePose, the current keyframe poses) and the ground-truth
/// T_W_C of the same frames, matched by their timestamps.
struct TrackingError {
  bool valid = false;       ///< tracked poses with ground truth for at least 3 frames
  std::size_t matched = 0;  ///< frames both trajectories have (every figure is over these)
  /// Absolute trajectory error after the SE(3) alignment (m): rmse, median, max.
  double ate_rmse_m = 0, ate_median_m = 0, ate_max_m = 0;
  /// Relative pose error (rmse) between consecutive matched frames (m, deg) and frames 1 s apart.
  double rpe_frame_m = 0, rpe_frame_deg = 0, rpe_second_m = 0, rpe_second_deg = 0;
  std::size_t rpe_second_pairs = 0;  ///< 0 when the trajectory is shorter than 1 s
};

/// Tracking error of the snapshot: invalid (all zero) unless it was mapped with tracked poses and
/// at least 3 of its frames have ground truth. Computed once per mapping generation (cached on
/// its inputs), so the UI may call it every frame. Thread-safe.
TrackingError trackingError(const MappingSnapshot& mapping);

}  // namespace vdmap::app::gui
