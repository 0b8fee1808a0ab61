#pragma once
// The OctoMap peer of `vdmap bench` (docs/method.md 12).
#include <octomap/Pointcloud.h>

#include "app/bench/bench_method.h"

namespace vdmap::app {

/// OctoMap at `res_m`: every frame's points (those the integrator uses, in the world frame)
/// inserted with a ray from the camera centre, each insertion's CPU time; the row's figure is
/// their median and its elements the occupied voxels at the finest resolution, scored by their
/// centres.
MethodResult timeOctomap(const BenchInput& in, double res_m);

/// The points the integrator uses (every pixel with depth in `range`), in the world frame: what
/// every OctoMap of `vdmap bench` inserts for one frame.
octomap::Pointcloud worldCloud(const RgbdFrame& frame, const PinholeCamera& cam, const DepthRange& range);

}  // namespace vdmap::app
