#pragma once
// The NDT-OM baseline of `vdmap bench` (app/bench/ndt_om_baseline.h, docs/method.md 12).
#include "app/bench/bench_method.h"

namespace vdmap::app {

/// The NDT-OM baseline at `res_m`: each frame's update CPU time; the row's figure is their
/// median and its elements the cells, scored by their means.
MethodResult timeNdtOm(const BenchInput& in, double res_m);

}  // namespace vdmap::app
