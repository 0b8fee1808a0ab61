#pragma once
// vdmap bench SEQ --query: the point queries (docs/method.md 13) against OctoMap on the same
// frames, for speed and, with --mesh and --truth, against ground truth (docs/performance.md and
// docs/results.md, "Queries").
#include <filesystem>

#include "app/bench/bench_method.h"

namespace vdmap::app {

/// Streams the frames of args.sequence (every frame unless --frames says otherwise) into vdmap's
/// Mapper (ground-truth poses) and every args.octomap_every-th frame into OctoMaps at 0.05 and
/// 0.02 m; builds the global map and its QueryMap; then, one thread, process CPU time, medians of
/// 3 passes: classify args.query_points points (half uniform in the seen box, half at global
/// ellipsoid means + N(0, 2 cm)) against OctoMap search + isNodeOccupied, distance on a tenth of
/// them, castView from args.views keyframe poses against OctoMap castRay per pixel, then vdmap's
/// queries in detail (query_detail.h). With
/// args.mesh and args.truth (the same poses rendered without noise), the accuracy of each map's
/// classification and distance on the OccupancyTruth sets, and each map's memory. Writes
/// bench.json (its `query` object) and bench.md into `out_dir` and the table to stdout.
void runQueryBench(const BenchArgs& args, const std::filesystem::path& out_dir);

}  // namespace vdmap::app
