#pragma once
// Loads the optional Open3D TSDF peer plugin (app/bench/open3d/tsdf_peer_abi.h) for `vdmap bench`.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mapping/core/camera.h"
#include "mapping/core/rgbd_frame.h"
#include "mapping/files/ply_reader.h"

namespace vdmap::app {

struct TsdfPeerApi;

/// One Open3D ScalableTSDFVolume driven through the plugin. Not thread-safe.
class TsdfVolume {
 public:
  ~TsdfVolume();
  TsdfVolume(const TsdfVolume&) = delete;
  TsdfVolume& operator=(const TsdfVolume&) = delete;

  /// The plugin beside the vdmap binary, or nullptr with *why saying what is missing.
  static std::unique_ptr<TsdfVolume> open(double voxel_m, double sdf_trunc_m, const PinholeCamera& camera,
                                          double depth_max_m, std::string* why);
  /// Integrates the frame at frame.T_W_C; returns Open3D's own time, ms.
  double integrate(const RgbdFrame& frame);
  /// Surface points of the volume (world frame, metres).
  std::vector<Eigen::Vector3f> extractPoints() const;
  /// The volume's triangle mesh (marching cubes; world frame, metres, vertex colours).
  ColoredTriangleMesh extractMesh() const;

 private:
  TsdfVolume(std::shared_ptr<const TsdfPeerApi> api, void* volume) : api_(std::move(api)), volume_(volume) {}
  std::shared_ptr<const TsdfPeerApi> api_;
  void* volume_;
};

}  // namespace vdmap::app
