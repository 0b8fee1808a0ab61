#pragma once
// One function draws a map view for the workbench and for `vdmap render`: the background, the
// map mirror (ellipsoids, graph lines) framed by view_framing, and the legend over it.
#include <opencv2/core.hpp>

#include "render/map_mirror.h"
#include "render/mesh_renderer.h"
#include "render/view_framing.h"
#include "render/view_spec.h"

namespace vdmap::render {

/// The bars around a letterboxed keyframe view.
inline constexpr glm::vec3 kLetterboxColor{0.05f, 0.05f, 0.06f};

/// The mirror's style for `spec` (colour, sigma, ellipsoids or centres, layers, splats, slice);
/// `height`: the map's height frame (heightFrame) the height colours measure from.
MirrorStyle mirrorStyle(const ViewSpec& spec, const HeightFrame& height = {});

/// Draws a map view into the bound framebuffer's rectangle `viewport` (GL pixels, from the
/// bottom-left): clears it (`background` in view.image, kLetterboxColor around it), draws `mesh`
/// (if any) and the mirror with `view.camera` in view.image, then the mirror's legend at the
/// image's bottom-left when `legend`. with_lines = false leaves the graph out.
void drawMapView(const Gl& gl, const MapMirror& mirror, const FramedView& view, const glm::vec3& background,
                 const PixelRect& viewport, bool with_lines, bool legend, const MeshRenderer* mesh = nullptr);

/// The headless path: `spec` drawn at width x height into a new framebuffer and read back as
/// CV_8UC3 RGB. The mirror holds the map, graph, legend (and for a container view the container)
/// already; its style is set from `spec` here.
cv::Mat renderView(const Gl& gl, MapMirror& mirror, const ViewSpec& spec, const ViewScene& scene, int width, int height,
                   const MeshRenderer* mesh = nullptr);

}  // namespace vdmap::render
