#include "app/bench/ndt_om_timing.h"

#include "app/bench/ndt_om_baseline.h"
#include "mapping/core/timing.h"

namespace vdmap::app {

MethodResult timeNdtOm(const BenchInput& in, double res_m) {
  MethodResult r = peerRow("NDT-OM baseline", "ndt_om", res_m);
  NdtOmParams p;
  p.resolution_m = res_m;
  p.depth_range = in.args.local_map.depth_range;
  NdtOmBaseline map(p);
  std::vector<double> ms;
  for (const RgbdFrame& f : in.frames) ms.push_back(cpuTimeMs([&] { map.integrateFrame(f, in.cam); }));
  r.ms = median(ms);
  in.score(&r, map.means());
  return r;
}

}  // namespace vdmap::app
