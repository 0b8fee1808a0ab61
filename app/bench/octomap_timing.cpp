#include "app/bench/octomap_timing.h"

#include <octomap/OcTree.h>

#include "app/view/progress.h"
#include "mapping/core/timing.h"

namespace vdmap::app {

octomap::Pointcloud worldCloud(const RgbdFrame& frame, const PinholeCamera& cam, const DepthRange& range) {
  const ColoredPointCloud cloud = toPointCloud(frame, cam, range);
  const Eigen::Isometry3f T = frame.T_W_C.cast<float>();
  octomap::Pointcloud out;
  out.reserve(cloud.size());
  for (const Eigen::Vector3f& p : cloud.points) {
    const Eigen::Vector3f w = T * p;
    out.push_back(w.x(), w.y(), w.z());
  }
  return out;
}

MethodResult timeOctomap(const BenchInput& in, double res_m) {
  MethodResult r = peerRow("OctoMap", "octomap", res_m);
  octomap::OcTree tree(res_m);
  std::vector<double> ms;
  ProgressBar progress(r.name, in.frames.size());
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    const octomap::Pointcloud cloud = worldCloud(in.frames[i], in.cam, in.args.local_map.depth_range);
    const Eigen::Vector3d c = in.frames[i].T_W_C.translation();
    ms.push_back(cpuTimeMs([&] { tree.insertPointCloud(cloud, octomap::point3d(c.x(), c.y(), c.z())); }));
    progress.update(i + 1);
  }
  r.ms = median(ms);
  // Elements: occupied voxels at the finest resolution (pruned blocks expanded), centres.
  tree.expand();
  std::vector<Eigen::Vector3f> centres;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    if (tree.isNodeOccupied(*it)) centres.emplace_back(it.getX(), it.getY(), it.getZ());
  in.score(&r, centres);
  return r;
}

}  // namespace vdmap::app
