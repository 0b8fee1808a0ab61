#pragma once
// vdmap bench SEQ --long: the long-run benchmark (docs/performance.md).
#include <filesystem>
#include <optional>

#include "mapping/global_map/global_map.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/sequence/sequence.h"

namespace vdmap::app {

struct LongRunOptions {
  int global_every = 500;  ///< frames between global-map builds (and one after the last frame)
  bool json = false;       ///< print long.json to stdout instead of the summary
};

/// Maps every frame of `seq` as `vdmap map` does (decoding and ORB on the prefetch thread, the
/// keyframe decision and update on this one) and records, per frame, this mapping thread's CPU
/// time and the Mapper's wall time, the process's resident memory and live heap, and the
/// keyframe count; every `global_every` frames it builds the global map and records its size and
/// t_g. Writes long.csv (one row per frame) and long.json (the summary: median CPU time per frame
/// over frames [N/6, N/3) and over the last N/6, i.e. 1000-2000 and the last 1000 of 6000, and
/// the resident memory at half way and at the end) into `out_dir`, which must exist.
/// With tracked poses (`mapper.poses`) the keyframe poses are refined after the last frame as
/// `refine` says, as `vdmap map` does, and long.json adds the tracking figures (addTrackingStats).
void runLongBench(const Sequence& seq, const MapperParams& mapper, const GlobalMapParams& global,
                  const std::filesystem::path& out_dir, const LongRunOptions& options,
                  const std::optional<MapRefinementParams>& refine);

}  // namespace vdmap::app
