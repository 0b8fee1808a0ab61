#pragma once
// What one frame says is free (docs/method.md 13.2), kept by the keyframe the frame was
// integrated into: space in front of the surface the frame measured, also where no keyframe's
// own view reaches (behind what the keyframe saw, beside its image).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mapping/core/camera.h"
#include "mapping/core/rgbd_frame.h"
#include "mapping/core/types.h"

namespace vdmap {

/// Pixels per side of a FrameFreeSpace block.
inline constexpr int kFreeBlockPx = 8;

struct FrameFreeSpace {
  Transform T_K_C = Transform::Identity();  ///< the frame's pose in its keyframe's frame
  int cols = 0, rows = 0;                   ///< blocks: ceil(width / kFreeBlockPx) x ceil(height / kFreeBlockPx)
  /// Per block (row-major), the nearest depth measured in it, mm rounded down; 0 when some pixel
  /// of the block has no depth within the depth range: then the block says nothing.
  std::vector<std::uint16_t> near_mm;

  std::size_t memoryBytes() const { return near_mm.capacity() * sizeof(std::uint16_t); }
};

/// A frame keeps its free space only when it stands at least kFreeSpaceStepM from, or looks at
/// least kFreeSpaceTurnRad away from, every frame its keyframe keeps: a frame next to a kept one
/// sees nearly the same space, and each kept frame costs memory and query time (docs/method.md 13.2).
inline constexpr double kFreeSpaceStepM = 0.02;
inline constexpr double kFreeSpaceTurnRad = 2.0 * 3.14159265358979323846 / 180.0;
bool addsFreeSpace(const std::vector<FrameFreeSpace>& kept, const Transform& T_K_C);

/// The blocks of `frame`'s depth image (CV_16UC1 of the camera's size; metres = value /
/// camera.depth_scale) at pose T_K_C in its keyframe.
FrameFreeSpace frameFreeSpace(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range,
                              const Transform& T_K_C);

}  // namespace vdmap
