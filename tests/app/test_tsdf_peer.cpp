// The Open3D TSDF peer of `vdmap bench` runs on one thread, as the comparison says it does.
// Open3D 0.16 sizes its OpenMP loops by the number of physical cores unless OMP_NUM_THREADS is
// set, whatever omp_set_num_threads() said; the plugin must see to that itself.
#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "app/bench/open3d/tsdf_peer_abi.h"

namespace {

std::size_t threadCount() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& task : std::filesystem::directory_iterator("/proc/self/task")) ++n;
  return n;
}

template <typename Fn>
Fn symbol(void* handle, const char* name) {
  return reinterpret_cast<Fn>(dlsym(handle, name));
}

TEST(TsdfPeer, IntegratesOnOneThread) {
  unsetenv("OMP_NUM_THREADS");  // the user's environment must not be what makes it single-threaded
  void* handle = dlopen(VDMAP_TSDF_PLUGIN, RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(handle, nullptr) << dlerror();
  const auto create = symbol<VdmapTsdfCreateFn>(handle, "vdmap_tsdf_create");
  const auto integrate = symbol<VdmapTsdfIntegrateFn>(handle, "vdmap_tsdf_integrate");
  const auto extract = symbol<VdmapTsdfExtractFn>(handle, "vdmap_tsdf_extract");
  const auto destroy = symbol<VdmapTsdfDestroyFn>(handle, "vdmap_tsdf_destroy");
  ASSERT_TRUE(create && integrate && extract && destroy);

  // A wall 1.5 m in front of a 640x480 camera looking down +z.
  const int w = 640, h = 480;
  void* volume = create(0.02, 0.08, w, h, 525, 525, 319.5, 239.5, 1000, 4.0);
  ASSERT_NE(volume, nullptr);
  const std::vector<std::uint8_t> rgb(3 * w * h, 128);
  const std::vector<std::uint16_t> depth(w * h, 1500);
  const Eigen::Matrix4d T_W_C = Eigen::Matrix4d::Identity();
  const std::size_t before = threadCount();
  // Each call reports its CPU time: positive, since the integration does work on this thread.
  for (int i = 0; i < 3; ++i) EXPECT_GT(integrate(volume, rgb.data(), depth.data(), T_W_C.data()), 0.0);
  EXPECT_EQ(threadCount(), before) << "Open3D started worker threads";

  std::vector<double> z;
  const std::size_t n = extract(
      volume,
      [](void* ctx, const double* xyz, std::size_t count) {
        for (std::size_t i = 0; i < count; ++i) static_cast<std::vector<double>*>(ctx)->push_back(xyz[3 * i + 2]);
      },
      &z);
  ASSERT_GT(n, 1000u);
  for (double zi : z) ASSERT_NEAR(zi, 1.5, 0.02);  // the surface within a voxel of the wall
  destroy(volume);
}

}  // namespace
