#pragma once
// The tracking rows of `vdmap bench --poses track` (docs/method.md 8, 12): vdmap's own tracking
// with and without loop closure, and the odometry peers (app/bench/odometry_peers.h), on the same
// frames, scored against their ground truth.
#include <filesystem>
#include <optional>
#include <vector>

#include "app/bench/bench_method.h"
#include "app/bench/odometry_peers.h"
#include "mapping/eval/trajectory_error.h"

namespace vdmap::app {

struct OdometryRow {
  OdometryRun run;
  double ms = 0.0;  ///< median CPU ms per registered frame
  std::optional<TrajectoryError> error;
};

/// The tracking table's rows in order, and what vdmap's loop-closure row adds beside them.
struct TrackingRows {
  std::vector<OdometryRow> rows;
  int loop_closures = 0;           ///< closed by vdmap with loop closure (the first row)
  MapRefinementResult refinement;  ///< its keyframe poses refined after the last frame (--refine)
};

/// Every tracking row on in.frames. Each row's trajectory is written to
/// trajectory_<key>.txt in `out_dir` (TUM), which is created.
TrackingRows timeTracking(const BenchInput& in, const std::filesystem::path& out_dir);

}  // namespace vdmap::app
