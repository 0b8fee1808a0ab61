#pragma once
#include <array>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "render/scene_types.h"

namespace vdmap::render {

/// A perceptual colour ramp (viridis, dark blue -> yellow) for t in [0, 1] (clamped).
glm::u8vec3 colormap(float t);
/// A distinct, stable colour per keyframe id: kKeyframePalette[k % 64], its lightness shifted
/// by +12 / -12 (CIELAB) in alternate later cycles of 64.
glm::u8vec3 keyframeColor(int keyframe);
/// The keyframe palette: 64 colours chosen greedily for the largest smallest CIELAB distance
/// (CIE76) among sRGB colours with lightness 45..85 (visible on the dark and the white
/// background); generateKeyframePalette computes it (a test checks the table against it).
inline constexpr int kKeyframePaletteSize = 64;
std::vector<glm::u8vec3> generateKeyframePalette(int n = kKeyframePaletteSize);
/// sRGB (0..255) -> CIELAB (D65), and back (clamped to the sRGB gamut).
glm::vec3 srgbToLab(const glm::u8vec3& rgb);
glm::u8vec3 labToSrgb(const glm::vec3& lab);
/// The colour of every ellipsoid under `mode`. Uncertainty uses log10(lambda_max) and count
/// uses log(count), both normalised to the set's own range so every map uses the whole ramp.
/// Height uses frame.height(mean) over heightRange(ellipsoids, frame, slice).
std::vector<glm::u8vec4> ellipsoidColors(std::span<const EllipsoidInstance> ellipsoids, ColorMode mode,
                                         const HeightFrame& frame = {}, const HeightSlice& slice = {});
/// The heights the height ramp spans: the slice's bounds when it is on, else the 2nd to 98th
/// percentile of the centres' heights above the floor ({0, 1} for no ellipsoids).
std::pair<float, float> heightRange(std::span<const EllipsoidInstance> ellipsoids, const HeightFrame& frame,
                                    const HeightSlice& slice);
/// The colour modes' names, indexed by ColorMode: the one list that the settings file, the
/// workbench and `vdmap render --color` use.
inline constexpr std::array<const char*, 5> kColorModeNames = {"rgb", "keyframe", "uncertainty", "count", "height"};
static_assert(kColorModeNames.size() == static_cast<std::size_t>(ColorMode::kHeight) + 1);
/// The name of `mode` in kColorModeNames.
const char* colorModeName(ColorMode mode);
/// Parses a name of kColorModeNames (throws std::invalid_argument naming them otherwise).
ColorMode parseColorMode(const std::string& name);

}  // namespace vdmap::render
