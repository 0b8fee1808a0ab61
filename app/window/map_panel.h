#pragma once
// The right panel: the thresholds, re-run parameters, tracking, view, keyframe, pick, pose
// correction, export and settings sections.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// Draws the "Map" panel at win.layout.right (its width follows the user's drag).
void drawMapPanel(Workbench& bench, const render::MapMirror& mirror, WindowState& win);

}  // namespace vdmap::app::gui
