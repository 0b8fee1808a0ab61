#pragma once
// Binary little-endian PLY exports (SPEC section 7).

#include <filesystem>
#include <vector>

#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap {

/// Writes ellipsoids as binary little-endian PLY: x y z float, red green blue uchar,
/// cxx cxy cxz cyy cyz czz float, count uint, keyframe int (SPEC section 7). Writes to a
/// temporary name in the same folder and renames it, so an interrupted export leaves no
/// half-written file. Throws std::runtime_error naming the file on an I/O failure.
void writeEllipsoidPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids);

/// Writes the ellipsoid means as a coloured point cloud: binary little-endian PLY, x y z float,
/// red green blue uchar (SPEC section 7). Atomic like writeEllipsoidPly.
void writePointPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids);

}  // namespace vdmap
