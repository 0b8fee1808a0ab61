#pragma once
// vdmap bench --ellipsoids N: the ellipsoid renderer alone on N random instanced ellipsoids,
// offscreen (docs/performance.md "Rendering").
#include "app/bench/bench_method.h"

namespace vdmap::app {

/// Draws `count` random ellipsoids (the same set every run: a fixed seed) in a 10 m cube with
/// `sphere_level` icosphere subdivisions (nullopt: the renderer's default), at draw.size
/// (default 1280x720) and draw.points_below; the upload once, then 5 frames from an eye that
/// moves 1 mm per frame, each glFinish-timed on the wall clock. Prints the renderer, the upload
/// and the median frame time (or, with `json`, the same as JSON); writes the last frame to
/// draw.png + ".png" when given. Throws when no offscreen context can be made.
void runEllipsoidBench(int count, std::optional<int> sphere_level, const DrawTimingOptions& draw, bool json);

}  // namespace vdmap::app
