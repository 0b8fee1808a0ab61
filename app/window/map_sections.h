#pragma once
// The Map panel's sections (map_panel.cpp draws them in this order), each in the file named for
// it: parameter_sections.cpp (Thresholds (live), Re-run parameters, Mesh), tracking_section.cpp,
// view_section.cpp, keyframes_section.cpp, picked_section.cpp, measure_section.cpp,
// queries_section.cpp, pose_correction_section.cpp, export_section.cpp, settings_section.cpp.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// "Thresholds (live)": the live parameters, then the global map's figures.
void drawThresholds(Workbench& bench, WindowState& win);
/// "Re-run parameters": the re-run parameters, Re-run and Revert.
void drawRerun(Workbench& bench, WindowState& win);
/// "Mesh": how the mesh layer's mesh is made (max slope, edge sigma, stride, fuse).
void drawMesh(Workbench& bench, WindowState& win);
/// "Tracking and loop closures" (tracked poses only): placed, lost and relocalised frames, the
/// ground truth and the tracking error, the loop closures and the map before the last
/// pose-graph optimisation.
void drawTracking(Workbench& bench, WindowState& win);
/// "View": colour, shape, up axis, what to show, the height slice; framing, help, the
/// screenshot and view files.
void drawView(Workbench& bench, WindowState& win);
/// "Keyframes": the list, then the selected keyframe's figures, container view, neighbours and
/// pose.
void drawKeyframes(Workbench& bench, const render::MapMirror& mirror, WindowState& win);
/// "Picked ellipsoid": the one clicked in the view.
void drawPicked(Workbench& bench, WindowState& win);
/// "Measure": both points, the distance, Copy, Clear, snap.
void drawMeasure(Workbench& bench, WindowState& win);
/// "Queries" (docs/workbench.md "Queries"): the probe (Q) and its offset, the query slice
/// (axis, offset, colour, samples) and what they were computed from.
void drawQueries(Workbench& bench, WindowState& win);
/// "Pose correction": a corrected TUM trajectory to load.
void drawPoseCorrection(Workbench& bench);
/// "Export and save": the export folder and the session file.
void drawExport(Workbench& bench, WindowState& win);
/// "Settings": reset to defaults, and where the settings come from and go to.
void drawSettings(Workbench& bench);

}  // namespace vdmap::app::gui
