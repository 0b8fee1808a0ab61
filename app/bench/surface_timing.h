#pragma once
// `vdmap bench SEQ --surfaces`: vdmap's surface mesh (docs/method.md 14) against Open3D's TSDF meshes
// on the same frames, each mesh written, timed, and with --mesh scored against the reference with the
// same sampler (evaluateSurfaceAccuracy).
#include <filesystem>

#include "app/bench/bench_method.h"

namespace vdmap::app {

/// Maps the frames (vdmap at the options' cell size, ground-truth poses; Open3D's TSDF at 0.02 and
/// 0.01 m, truncation 4 voxels), writes surface_vdmap.ply, surface_open3d_0.02.ply and
/// surface_open3d_0.01.ply into out_dir, prints the table and writes surfaces.json. Completion counts
/// reference samples within 2 cm. One thread.
void runSurfaceBench(const BenchInput& in, const std::filesystem::path& out_dir);

}  // namespace vdmap::app
