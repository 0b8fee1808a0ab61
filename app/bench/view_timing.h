#pragma once
// vdmap bench MAP --view: the 3-D view's frame times on a saved session or map, offscreen
// (docs/performance.md "Workbench").
#include <string>

#include "app/bench/bench_method.h"

namespace vdmap::app {

/// Opens `map` (anything `vdmap render --map` opens; throws InputError naming it otherwise) and
/// draws its global map in the offscreen (OSMesa) context at draw.size (default 752x870, the 3-D
/// viewport of a 1600x900 window): the upload (and of it the LOD order), options.steps orbit
/// steps at full quality and with the fast pass for each budget (the LOD prefix of K
/// ellipsoids), the settle frame (the full frame into the view image cache after the camera
/// stops) and a frame the cache only copies. Frames are glFinish-timed, wall clock and process
/// CPU; the first step of each pass (shader compilation, first upload) is left out. Prints the
/// medians and the instances per frame (or, with `json`, the same as JSON); with draw.png writes
/// PREFIX_full.png and PREFIX_fast_K.png of the last step.
void runViewBench(const std::string& map, const ViewTimingOptions& options, const DrawTimingOptions& draw, bool json);

}  // namespace vdmap::app
