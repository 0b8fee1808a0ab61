#pragma once
// Opening files in the window (docs/workbench.md "Opening files"): the Open field with its
// recent files, and what the panels show for a map file (a static map) in place of what it lacks.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// The Open field (any kind the workbench opens), Open, Browse... (the file browser), and the
/// Recent combo: settings' recent paths, newest first, those no longer there greyed.
void drawOpenArea(Workbench& bench, WindowState& win);
/// The open map file's figures (kind, ellipsoids, keyframes, edges, trajectory, sigma of points,
/// and the `vdmap map` stats a map folder carries) in place of the global map's build figures.
void drawStaticMapFigures(const Workbench& bench, WindowState& win);

}  // namespace vdmap::app::gui
