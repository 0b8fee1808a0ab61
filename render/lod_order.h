#pragma once
// The level-of-detail order of a map for the 3-D view's fast pass (docs/performance.md
// "Workbench"): a permutation of the ellipsoids whose every prefix is a spatially even sample, so
// that drawing the first K of them while the camera moves shows the whole map, thinned.
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap::render {

/// Cell sizes of the order's levels, coarsest first, metres.
inline constexpr float kLodCellSizesM[] = {0.32f, 0.16f, 0.08f, 0.04f};

/// A permutation of 0..n-1 of the centres: first one centre per occupied 32 cm cell, then one
/// per 16 cm cell not yet represented, then 8 cm and 4 cm, then the rest; within a level in index
/// order (the first centre of each cell). Deterministic; O(n) per level (a hash of cell keys).
/// Non-finite centres come last.
std::vector<std::uint32_t> lodOrder(std::span<const glm::vec3> centres);
/// The order of a map's ellipsoids as the 3-D view draws them (their means in float, as
/// toInstances gives them; the same order): computed where the map is built, off the UI thread.
std::vector<std::uint32_t> lodOrder(std::span<const Ellipsoid> ellipsoids);

}  // namespace vdmap::render
