#include "app/bench/tsdf_peer.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "app/bench/open3d/tsdf_peer_abi.h"
#include "app/bench/peer_plugin.h"

namespace vdmap::app {

struct TsdfPeerApi {
  VdmapTsdfCreateFn create = nullptr;
  VdmapTsdfIntegrateFn integrate = nullptr;
  VdmapTsdfExtractFn extract = nullptr;
  VdmapTsdfExtractMeshFn extract_mesh = nullptr;
  VdmapTsdfDestroyFn destroy = nullptr;
};

namespace {

std::shared_ptr<const TsdfPeerApi> loadApi(std::string* why) {
  auto a = std::make_shared<TsdfPeerApi>();
  a->create = reinterpret_cast<VdmapTsdfCreateFn>(open3dPeerSymbol("vdmap_tsdf_create", why));
  a->integrate = reinterpret_cast<VdmapTsdfIntegrateFn>(open3dPeerSymbol("vdmap_tsdf_integrate", why));
  a->extract = reinterpret_cast<VdmapTsdfExtractFn>(open3dPeerSymbol("vdmap_tsdf_extract", why));
  a->extract_mesh = reinterpret_cast<VdmapTsdfExtractMeshFn>(open3dPeerSymbol("vdmap_tsdf_extract_mesh", why));
  a->destroy = reinterpret_cast<VdmapTsdfDestroyFn>(open3dPeerSymbol("vdmap_tsdf_destroy", why));
  if (!a->create || !a->integrate || !a->extract || !a->extract_mesh || !a->destroy) return nullptr;
  return a;
}

}  // namespace

std::unique_ptr<TsdfVolume> TsdfVolume::open(double voxel_m, double sdf_trunc_m, const PinholeCamera& cam,
                                             double depth_max_m, std::string* why) {
  std::shared_ptr<const TsdfPeerApi> api = loadApi(why);
  if (!api) return nullptr;
  void* v = api->create(voxel_m, sdf_trunc_m, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy, cam.depth_scale,
                        depth_max_m);
  if (!v) {
    *why = "Open3D could not create the TSDF volume";
    return nullptr;
  }
  return std::unique_ptr<TsdfVolume>(new TsdfVolume(api, v));
}

TsdfVolume::~TsdfVolume() { api_->destroy(volume_); }

double TsdfVolume::integrate(const RgbdFrame& frame) {
  const cv::Mat rgb = frame.rgb.isContinuous() ? frame.rgb : frame.rgb.clone();
  const cv::Mat depth = frame.depth.isContinuous() ? frame.depth : frame.depth.clone();
  const Eigen::Matrix4d T = frame.T_W_C.matrix();
  return api_->integrate(volume_, rgb.ptr<std::uint8_t>(), depth.ptr<std::uint16_t>(), T.data());
}

std::vector<Eigen::Vector3f> TsdfVolume::extractPoints() const {
  std::vector<Eigen::Vector3f> out;
  api_->extract(
      volume_,
      [](void* ctx, const double* xyz, std::size_t n) {
        auto* points = static_cast<std::vector<Eigen::Vector3f>*>(ctx);
        for (std::size_t i = 0; i < n; ++i) points->emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      },
      &out);
  return out;
}

ColoredTriangleMesh TsdfVolume::extractMesh() const {
  ColoredTriangleMesh out;
  api_->extract_mesh(
      volume_,
      [](void* ctx, const double* xyz, const double* rgb, std::size_t n, const int* tri, std::size_t t) {
        auto* mesh = static_cast<ColoredTriangleMesh*>(ctx);
        for (std::size_t i = 0; i < n; ++i) {
          mesh->positions.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
          std::array<std::uint8_t, 3> c;
          for (std::size_t k = 0; k < 3; ++k)
            c[k] = static_cast<std::uint8_t>(std::clamp(std::lround(255.0 * rgb[3 * i + k]), 0L, 255L));
          mesh->colors.push_back(c);
        }
        for (std::size_t i = 0; i < t; ++i)
          mesh->triangles.push_back({static_cast<std::uint32_t>(tri[3 * i]), static_cast<std::uint32_t>(tri[3 * i + 1]),
                                     static_cast<std::uint32_t>(tri[3 * i + 2])});
      },
      &out);
  return out;
}

}  // namespace vdmap::app
