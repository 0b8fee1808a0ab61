#pragma once
// The right panel's tracking section: placed, lost and relocalised frames, the ground truth, the
// loop closures and the map before the last pose-graph optimisation.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// The "Tracking and loop closures" section (tracked poses only).
void drawTracking(Workbench& bench, WindowState& win);

}  // namespace vdmap::app::gui
