#pragma once
// Shared by the Open3D peers: the plugin interface's packed frame as Open3D images.
#include <cstdint>
#include <cstring>

#include <open3d/geometry/Image.h>

namespace vdmap::peers {

/// rgb: 8-bit RGB rows, depth: 16-bit rows, both w x h packed, copied into Open3D images.
inline void toOpen3dImages(const std::uint8_t* rgb, const std::uint16_t* depth, int w, int h,
                           open3d::geometry::Image* color, open3d::geometry::Image* depth_image) {
  color->Prepare(w, h, 3, 1);
  depth_image->Prepare(w, h, 1, 2);
  std::memcpy(color->data_.data(), rgb, 3 * w * h);
  std::memcpy(depth_image->data_.data(), depth, sizeof(std::uint16_t) * w * h);
}

}  // namespace vdmap::peers
