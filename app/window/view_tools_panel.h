#pragma once
// View tools in the View section: the height slice (docs/workbench.md "View").
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// The height slice: "Slice" on/off, its heights above the floor (m), and "Frame slice". The
/// same slice as `vdmap render --slice` (settings keys slice, slice_lo, slice_hi); PgUp / PgDn
/// move it by its thickness.
void drawSliceControls(Workbench& bench, WindowState& win);

/// The Queries section (docs/workbench.md "Queries"): the probe (Q) and its offset, the query
/// slice (axis, offset, colour, samples) and what they were computed from.
void drawQueries(Workbench& bench, WindowState& win);

}  // namespace vdmap::app::gui
