#pragma once
// The right panel ("Map"): its sections in order, each drawn in its own file (map_sections.h).
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// Draws the "Map" panel at win.layout.right (its width follows the user's drag).
void drawMapPanel(Workbench& bench, const render::MapMirror& mirror, WindowState& win);

}  // namespace vdmap::app::gui
