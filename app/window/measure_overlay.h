#pragma once
// The 3-D view's tools drawn over it with Dear ImGui: the picked ellipsoid's marker, measuring
// (Ctrl+click A, then B), zoom toward the cursor and the pivot under it (wheel, double-click, P),
// which read the view's depth under the cursor after the scene is drawn (render::readDepth).
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "app/window/window_state.h"
#include "render/gl.h"

namespace vdmap::app::gui {

/// Mouse actions over the 3-D view that need the point under the cursor: queued as probes
/// (answerProbes answers them once the scene is drawn). Call after handleMouse.
void handleViewTools(Workbench& bench, WindowState& win);
/// The world point drawn at pixel (x, y) of the 3-D viewport (framebuffer pixels, top-left
/// origin), read from the depth buffer of the scene just drawn; nullopt where nothing is drawn.
std::optional<glm::vec3> probeView(Workbench& bench, const render::Gl& gl, const WindowState& win, float x_px,
                                   float y_px);
/// Answers the queued probes (zoom toward, pivot at, measure at the point, the point queries'
/// probe): after drawScene. Returns whether what the view shows changed (the probe's text).
bool answerProbes(Workbench& bench, const render::Gl& gl, WindowState& win);
/// The pick marker and the measured line over the 3-D view.
void drawViewMarks(Workbench& bench, const WindowState& win);
/// "0.842 m (dx dy dz)": the distance from `a` to `b` and its components along the world axes, as
/// the measured line and the Measure section print it.
std::string distanceText(const glm::vec3& a, const glm::vec3& b);

}  // namespace vdmap::app::gui
