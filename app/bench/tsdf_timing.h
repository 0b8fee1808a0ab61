#pragma once
// The Open3D TSDF peer of `vdmap bench`, through its optional plugin (app/bench/tsdf_peer.h).
#include "app/bench/bench_method.h"

namespace vdmap::app {

/// Open3D's TSDF at `voxel_m` (truncation 4 voxels): each frame's integration time as the plugin
/// measures it; the row's figure is their median and its elements the extracted surface points.
/// Without the plugin the row says why in its note.
MethodResult timeOpen3dTsdf(const BenchInput& in, double voxel_m);

}  // namespace vdmap::app
