#pragma once
// The large container view of the selected keyframe (C): zoom, pan, cell grid and image bounds.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// Draws it while ui().show_container and the mirror holds a container image.
void drawContainerWindow(Workbench& bench, const render::MapMirror& mirror, WindowState& win);

}  // namespace vdmap::app::gui
