#pragma once
// The right panel's parameter sections (live thresholds with the global map's figures, re-run
// parameters) and its view options.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// The "Thresholds (live)" section: the live parameters, then the global map's figures.
void drawThresholds(Workbench& bench, WindowState& win);
/// The "Re-run parameters" section: the re-run parameters, Re-run and Revert.
void drawRerun(Workbench& bench, WindowState& win);
/// The "View" section: colour, shape, up axis, what to show; framing, help and the screenshot.
void drawView(Workbench& bench, WindowState& win);

}  // namespace vdmap::app::gui
