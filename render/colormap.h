#pragma once
#include <span>
#include <string>
#include <vector>

#include "render/scene_types.h"

namespace vdmap::render {

/// A perceptual colour ramp (viridis, dark blue -> yellow) for t in [0, 1] (clamped).
glm::u8vec3 colormap(float t);
/// A distinct, stable colour per keyframe id (golden-ratio hue steps).
glm::u8vec3 keyframeColor(int keyframe);
/// The colour of every ellipsoid under `mode`. Uncertainty uses log10(lambda_max) and count
/// uses log(count), both normalised to the set's own range so every map uses the whole ramp.
std::vector<glm::u8vec4> ellipsoidColors(std::span<const EllipsoidInstance> ellipsoids, ColorMode mode);
/// Parses "rgb", "keyframe", "uncertainty", "count" (throws std::invalid_argument otherwise).
ColorMode parseColorMode(const std::string& name);

}  // namespace vdmap::render
