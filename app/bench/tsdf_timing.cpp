#include "app/bench/tsdf_timing.h"

#include <memory>

#include "app/bench/tsdf_peer.h"
#include "app/view/progress.h"
#include "mapping/core/timing.h"

namespace vdmap::app {

MethodResult timeOpen3dTsdf(const BenchInput& in, double voxel_m) {
  MethodResult r = peerRow("Open3D TSDF", "open3d_tsdf", voxel_m);
  // Truncation of 4 voxels, Open3D's examples' ratio (0.04 m at ~0.01 m voxels).
  std::unique_ptr<TsdfVolume> volume =
      TsdfVolume::open(voxel_m, 4 * voxel_m, in.cam, in.args.local_map.depth_range.max_m, &r.note);
  if (!volume) return r;
  std::vector<double> ms;
  ProgressBar progress(r.name, in.frames.size());
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    ms.push_back(volume->integrate(in.frames[i]));
    progress.update(i + 1);
  }
  r.ms = median(ms);
  in.score(&r, volume->extractPoints());
  return r;
}

}  // namespace vdmap::app
