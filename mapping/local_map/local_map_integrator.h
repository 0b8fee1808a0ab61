#pragma once
// Integrates RGB-D frames into a keyframe's view-dependent container (SPEC section 2).

#include <cstdint>
#include <vector>

#include "mapping/core/rgbd_frame.h"
#include "mapping/local_map/keyframe_container.h"

namespace vdmap {

/// Parameters of the local maps (SPEC section 9). Changing them means rebuilding local maps.
struct LocalMapParams {
  int cell_size_px = 5;
  DepthRange depth_range;
};

/// Updates a container with every valid pixel of a frame (no subsampling). Holds scratch
/// buffers so that no memory is allocated per frame once warm; one integrator per thread.
/// Single-threaded and deterministic: the touched cells come out in the order of first touch
/// in a row-major scan of the frame.
class LocalMapIntegrator {
 public:
  explicit LocalMapIntegrator(const LocalMapParams& params = {}) : params_(params) {}

  /// Back-projects each pixel of `frame` with depth in params.depth_range (camera `camera`),
  /// moves it into the keyframe frame with T_K_C = T_W_K^-1 * frame.T_W_C, projects it with the
  /// container's camera, and merges the points of each cell as one batch. Points with z <= 0
  /// or outside the container are dropped. `touched_cells` (may be null) receives the grid
  /// index of every cell that received points, in order of first touch.
  /// A frame without valid depth is a no-op (touched_cells empty).
  /// Throws std::invalid_argument when a pose is not a finite rigid transform, the depth image
  /// is not CV_16UC1 of the camera's size, or a non-empty colour image is not CV_8UC3 of that
  /// size. Cell size and container layout are the container's own.
  void integrateFrame(const RgbdFrame& frame, const PinholeCamera& camera, const Transform& T_W_K,
                      KeyframeContainer* container, std::vector<int>* touched_cells);

  const LocalMapParams& params() const { return params_; }

 private:
  // Per-cell sums of one frame, relative to `origin` (the cell's first point in this frame) so
  // that the scatter S_N = Q - q q^T / N does not cancel catastrophically far from the camera.
  struct FrameSums {
    double origin[3];
    double n;
    double q[3];   // sum (p - origin)
    double Q[6];   // sum (p - origin)(p - origin)^T: xx xy xz yy yz zz
    double c[3];   // colour sums
  };

  LocalMapParams params_;
  std::vector<std::int32_t> sums_slot_;  // per grid cell: index into sums_, or -1
  std::vector<FrameSums> sums_;          // sized to the grid once; the first used_ are live
  std::vector<int> used_cells_;          // grid index of sums_[i]
  std::vector<double> ray_x_, ray_y_, ray_z_;  // per column: ((u - cx) / fx) * R.col(0)
  std::vector<double> row_x_, row_y_, row_z_;  // one row's p_K
  std::vector<int> row_cell_;                  // one row's cells (-1: no point)
};

}  // namespace vdmap
