// The Open3D odometry peer of `vdmap bench --poses track`: Open3D 0.16's RGB-D
// odometry with the hybrid (photometric + geometric) Jacobian, frame to frame as in Open3D's
// own examples, with its default options (pyramid iterations 20/10/5, depth 0-4 m, depth
// difference 0.03 m).
#include <cstdlib>
#include <cstring>
#include <memory>

#include <omp.h>
#include <open3d/Open3D.h>

#include "app/bench/open3d/odometry_peer_abi.h"
#include "app/bench/open3d/open3d_images.h"

namespace {

struct Odometry {
  open3d::camera::PinholeCameraIntrinsic intrinsic;
  double depth_scale;
  open3d::pipelines::odometry::OdometryOption option;
  std::shared_ptr<open3d::geometry::RGBDImage> previous;
};

}  // namespace

extern "C" {

void* vdmap_odometry_create(int width, int height, double fx, double fy, double cx, double cy, double depth_scale) {
  // One thread, as every peer of the bench (see vdmap_tsdf_create for why the variable is set).
  setenv("OMP_NUM_THREADS", "1", /*overwrite=*/0);
  omp_set_num_threads(1);
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  try {
    return new Odometry{
        open3d::camera::PinholeCameraIntrinsic(width, height, fx, fy, cx, cy), depth_scale, {}, nullptr};
  } catch (...) {
    return nullptr;
  }
}

int vdmap_odometry_track(void* odometry, const std::uint8_t* rgb, const std::uint16_t* depth, double* T_prev_cur) {
  auto* o = static_cast<Odometry*>(odometry);
  open3d::geometry::Image color, depth_image;
  vdmap::peers::toOpen3dImages(rgb, depth, o->intrinsic.width_, o->intrinsic.height_, &color, &depth_image);
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  bool success = true;
  // Odometry wants float intensity (convert_rgb_to_intensity) and depth in metres.
  std::shared_ptr<open3d::geometry::RGBDImage> current = open3d::geometry::RGBDImage::CreateFromColorAndDepth(
      color, depth_image, o->depth_scale, o->option.depth_max_, true);
  if (o->previous) {
    // Source = this frame, target = the previous one: the result maps this frame's points into
    // the previous frame, T_prev_cur.
    const auto [converged, T_target_source, information] = open3d::pipelines::odometry::ComputeRGBDOdometry(
        *current, *o->previous, o->intrinsic, Eigen::Matrix4d::Identity(),
        open3d::pipelines::odometry::RGBDOdometryJacobianFromHybridTerm(), o->option);
    success = converged;
    if (converged) T = T_target_source;
  }
  o->previous = current;
  std::memcpy(T_prev_cur, T.data(), 16 * sizeof(double));
  return success ? 1 : 0;
}

void vdmap_odometry_destroy(void* odometry) { delete static_cast<Odometry*>(odometry); }
}

static_assert(std::is_same_v<decltype(&vdmap_odometry_create), VdmapOdometryCreateFn>);
static_assert(std::is_same_v<decltype(&vdmap_odometry_track), VdmapOdometryTrackFn>);
static_assert(std::is_same_v<decltype(&vdmap_odometry_destroy), VdmapOdometryDestroyFn>);
