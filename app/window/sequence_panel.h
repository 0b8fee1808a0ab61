#pragma once
// The left panel: what is open, the player and its scrubber (keyframe ticks, loop markers), the
// last mapped frame's images and the mapping stages' times.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// Draws the "Sequence" panel at win.layout.left (its width follows the user's drag).
void drawSequencePanel(Workbench& bench, const render::MapMirror& mirror, WindowState& win);

}  // namespace vdmap::app::gui
