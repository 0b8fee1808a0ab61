// The Open3D peer of `vdmap bench` (the TSDF rows): Open3D 0.16's ScalableTSDFVolume, built as a
// plugin only when Open3D is installed (see app/bench/open3d/tsdf_peer_abi.h for why it is a plugin).
#include <cstdlib>
#include <cstring>
#include <memory>

#include <omp.h>
#include <open3d/Open3D.h>

#include "app/bench/open3d/open3d_images.h"
#include "app/bench/open3d/tsdf_peer_abi.h"
#include "mapping/core/timing.h"

namespace {

struct Volume {
  open3d::pipelines::integration::ScalableTSDFVolume tsdf;
  open3d::camera::PinholeCameraIntrinsic intrinsic;
  double depth_scale, depth_max_m;
  Volume(double voxel_m, double trunc_m, int w, int h, double fx, double fy, double cx, double cy, double depth_scale,
         double depth_max_m)
      : tsdf(voxel_m, trunc_m, open3d::pipelines::integration::TSDFVolumeColorType::RGB8),
        intrinsic(w, h, fx, fy, cx, cy), depth_scale(depth_scale), depth_max_m(depth_max_m) {}
};

}  // namespace

extern "C" {

void* vdmap_tsdf_create(double voxel_m, double sdf_trunc_m, int width, int height, double fx, double fy, double cx,
                        double cy, double depth_scale, double depth_max_m) {
  // The comparison is single-threaded (vdmap's integrator and liboctomap are); Open3D's
  // integration loop is OpenMP. Open3D 0.16 sizes its parallel loops with
  // utility::EstimateMaxThreads(), which ignores omp_set_num_threads() and returns the number of
  // physical cores unless OMP_NUM_THREADS is set. Without the variable the "one-thread" TSDF ran
  // on every core, and process CPU time counted the spinning workers, the more the busier the
  // machine (docs/notes/performance.md).
  setenv("OMP_NUM_THREADS", "1", /*overwrite=*/0);
  omp_set_num_threads(1);
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  try {
    return new Volume(voxel_m, sdf_trunc_m, width, height, fx, fy, cx, cy, depth_scale, depth_max_m);
  } catch (...) {
    return nullptr;
  }
}

double vdmap_tsdf_integrate(void* volume, const std::uint8_t* rgb, const std::uint16_t* depth, const double* T_W_C) {
  auto* v = static_cast<Volume*>(volume);
  open3d::geometry::Image color, depth_image;
  vdmap::peers::toOpen3dImages(rgb, depth, v->intrinsic.width_, v->intrinsic.height_, &color, &depth_image);
  const Eigen::Matrix4d T_C_W = Eigen::Map<const Eigen::Matrix4d>(T_W_C).inverse();
  std::shared_ptr<open3d::geometry::RGBDImage> rgbd;  // freed after the timed part
  return vdmap::cpuTimeMs([&] {
    rgbd =
        open3d::geometry::RGBDImage::CreateFromColorAndDepth(color, depth_image, v->depth_scale, v->depth_max_m, false);
    v->tsdf.Integrate(*rgbd, v->intrinsic, T_C_W);
  });
}

std::size_t vdmap_tsdf_extract(void* volume, void (*sink)(void*, const double*, std::size_t), void* ctx) {
  const auto cloud = static_cast<Volume*>(volume)->tsdf.ExtractPointCloud();
  const std::size_t n = cloud->points_.size();
  sink(ctx, n ? cloud->points_[0].data() : nullptr, n);  // std::vector<Eigen::Vector3d>: packed xyz
  return n;
}

std::size_t vdmap_tsdf_extract_mesh(
    void* volume, void (*sink)(void*, const double*, const double*, std::size_t, const int*, std::size_t), void* ctx) {
  const auto mesh = static_cast<Volume*>(volume)->tsdf.ExtractTriangleMesh();
  const std::size_t n = mesh->vertices_.size(), t = mesh->triangles_.size();
  const bool colours = mesh->vertex_colors_.size() == n;
  std::vector<Eigen::Vector3d> grey;
  if (!colours) grey.assign(n, Eigen::Vector3d::Constant(0.8));
  // std::vector<Eigen::Vector3d> and <Eigen::Vector3i>: packed triples.
  sink(ctx, n ? mesh->vertices_[0].data() : nullptr, n ? (colours ? mesh->vertex_colors_ : grey)[0].data() : nullptr, n,
       t ? mesh->triangles_[0].data() : nullptr, t);
  return t;
}

void vdmap_tsdf_destroy(void* volume) { delete static_cast<Volume*>(volume); }
}

// The plugin's functions must match the interface vdmap loads them by.
static_assert(std::is_same_v<decltype(&vdmap_tsdf_create), VdmapTsdfCreateFn>);
static_assert(std::is_same_v<decltype(&vdmap_tsdf_integrate), VdmapTsdfIntegrateFn>);
static_assert(std::is_same_v<decltype(&vdmap_tsdf_extract), VdmapTsdfExtractFn>);
static_assert(std::is_same_v<decltype(&vdmap_tsdf_extract_mesh), VdmapTsdfExtractMeshFn>);
static_assert(std::is_same_v<decltype(&vdmap_tsdf_destroy), VdmapTsdfDestroyFn>);
