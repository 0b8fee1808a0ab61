#include "app/tsdf_peer.h"

#include <dlfcn.h>

#include <filesystem>

#include "peers/tsdf_peer_abi.h"

namespace vdmap::app {

struct TsdfPeerApi {
  void* handle = nullptr;
  VdmapTsdfCreateFn create = nullptr;
  VdmapTsdfIntegrateFn integrate = nullptr;
  VdmapTsdfExtractFn extract = nullptr;
  VdmapTsdfDestroyFn destroy = nullptr;
  // The library stays loaded for the life of the process: Open3D registers atexit handlers and
  // static destructors that must not outlive their code.
};

namespace {

std::shared_ptr<const TsdfPeerApi> loadApi(std::string* why) {
  static std::shared_ptr<const TsdfPeerApi> api;
  static std::string error;
  if (api || !error.empty()) {
    *why = error;
    return api;
  }
  const std::filesystem::path plugin =
      std::filesystem::read_symlink("/proc/self/exe").parent_path() / "libvdmap_open3d_peer.so";
  auto a = std::make_shared<TsdfPeerApi>();
  // RTLD_LOCAL: Open3D's symbols (and the GL libraries it pulls in) do not join the global
  // namespace the renderer resolves through.
  a->handle = dlopen(plugin.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!a->handle) {
    error = std::filesystem::exists(plugin) ? std::string(dlerror())
                                            : plugin.string() + " not built (configure with libopen3d-dev installed)";
    *why = error;
    return nullptr;
  }
  a->create = reinterpret_cast<VdmapTsdfCreateFn>(dlsym(a->handle, "vdmap_tsdf_create"));
  a->integrate = reinterpret_cast<VdmapTsdfIntegrateFn>(dlsym(a->handle, "vdmap_tsdf_integrate"));
  a->extract = reinterpret_cast<VdmapTsdfExtractFn>(dlsym(a->handle, "vdmap_tsdf_extract"));
  a->destroy = reinterpret_cast<VdmapTsdfDestroyFn>(dlsym(a->handle, "vdmap_tsdf_destroy"));
  if (!a->create || !a->integrate || !a->extract || !a->destroy) {
    error = plugin.string() + ": missing vdmap_tsdf_* functions";
    *why = error;
    return nullptr;
  }
  api = a;
  return api;
}

}  // namespace

std::unique_ptr<TsdfVolume> TsdfVolume::open(double voxel_m, double sdf_trunc_m, const PinholeCamera& cam,
                                             double depth_max_m, std::string* why) {
  std::shared_ptr<const TsdfPeerApi> api = loadApi(why);
  if (!api) return nullptr;
  void* v = api->create(voxel_m, sdf_trunc_m, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy,
                        cam.depth_scale, depth_max_m);
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

}  // namespace vdmap::app
