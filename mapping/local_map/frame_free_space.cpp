#include "mapping/local_map/frame_free_space.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace vdmap {

bool addsFreeSpace(const std::vector<FrameFreeSpace>& kept, const Transform& T_K_C) {
  for (const FrameFreeSpace& f : kept) {
    const Transform delta = f.T_K_C.inverse() * T_K_C;
    if (delta.translation().norm() < kFreeSpaceStepM && Eigen::AngleAxisd(delta.linear()).angle() < kFreeSpaceTurnRad)
      return false;
  }
  return true;
}

FrameFreeSpace frameFreeSpace(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range,
                              const Transform& T_K_C) {
  FrameFreeSpace out;
  out.T_K_C = T_K_C;
  out.cols = (camera.width + kFreeBlockPx - 1) / kFreeBlockPx;
  out.rows = (camera.height + kFreeBlockPx - 1) / kFreeBlockPx;
  constexpr std::uint16_t kNone = 0, kUnset = std::numeric_limits<std::uint16_t>::max();
  out.near_mm.assign(static_cast<std::size_t>(out.cols) * out.rows, kUnset);
  // Raw depth units in range, and raw -> mm rounded down (never nearer than measured: the free
  // space ends no later than the surface).
  const double lo = std::ceil(range.min_m * camera.depth_scale), hi = std::floor(range.max_m * camera.depth_scale);
  const double mm_per_unit = 1000.0 / camera.depth_scale;
  for (int v = 0; v < camera.height; ++v) {
    const std::uint16_t* row = frame.depth.ptr<std::uint16_t>(v);
    std::uint16_t* block = &out.near_mm[static_cast<std::size_t>(v / kFreeBlockPx) * out.cols];
    for (int u = 0; u < camera.width; ++u) {
      std::uint16_t& b = block[u / kFreeBlockPx];
      if (b == kNone) continue;
      const double raw = row[u];
      if (!(raw >= lo && raw <= hi && raw > 0)) {
        b = kNone;
        continue;
      }
      const double mm = std::min(std::floor(raw * mm_per_unit), double{kUnset - 1});
      b = std::min(b, static_cast<std::uint16_t>(mm));
    }
  }
  return out;
}

}  // namespace vdmap
