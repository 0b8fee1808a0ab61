#pragma once
#include <string_view>

namespace vdmap::render {

/// The text of shaders/NAME (e.g. "ellipsoid.vert"), embedded at build time. Throws
/// std::invalid_argument for an unknown name.
std::string_view shaderSource(std::string_view name);

}  // namespace vdmap::render
