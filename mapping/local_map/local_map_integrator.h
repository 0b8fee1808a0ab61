#pragma once
// Integrates RGB-D frames into a keyframe's view-dependent container (docs/method.md 2).

#include <cstdint>
#include <vector>

#include "mapping/core/rgbd_frame.h"
#include "mapping/local_map/keyframe_container.h"

namespace vdmap {

/// Parameters of the local maps (docs/parameters.md). Changing them means rebuilding local maps.
struct LocalMapParams {
  int cell_size_px = 5;
  DepthRange depth_range;
};

namespace detail {
// GCC vector: AVX where the CPU has it. Its alignment depends on the ISA (16 without AVX), so
// the structs holding it say alignas(32) explicitly.
using V4d = double __attribute__((vector_size(32)));
// Per-cell sums of one frame, of r = p_K - t (t: the frame's camera centre in K):
// q = sum (r, 1), xp = sum r.x (r, 1), yp = sum r.y (r, 1), zz = sum r.z^2. Points lie within the
// depth range of t, so in double the scatter S_N = Q - q q^T / N loses ~eps (z / w)^2 of an entry
// of width w at depth z: 1e-11 of the large entries (w = the cell's footprint), 1e-6 of the
// thinnest in the worst case (8 m, 0.1 mm spread; real sensor noise there is ~10 cm). Colour
// sums are exact integers (at most 255 * 640 * 480 < 2^32).
struct alignas(32) FrameSums {
  V4d q, xp, yp;
  double zz;
  std::uint32_t c[3];
};
}  // namespace detail

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
  LocalMapParams params_;
  std::vector<std::int32_t> sums_slot_;        // per grid cell: index into sums_, or -1
  std::vector<detail::FrameSums> sums_;        // sized to the grid once; the first used_cells_.size() are live
  std::vector<int> used_cells_;                // grid index of sums_[i]
  std::vector<double> ray_x_, ray_y_, ray_z_;  // per column: ((u - cx) / fx) * R.col(0)
  std::vector<double> row_x_, row_y_, row_z_;  // one row's p_K - t
  std::vector<int> row_cell_;                  // one row's cells (-1: no point)
};

}  // namespace vdmap
