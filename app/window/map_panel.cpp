#include "app/window/map_panel.h"

#include "app/window/map_sections.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {

void drawMapPanel(Workbench& bench, const render::MapMirror& mirror, WindowState& win) {
  beginPanel("Map", win.layout.right, win.layout.right_w, win.layout.last_size.x);
  if (bench.isOpen()) {
    if (section(win.check, "Thresholds (live)", true)) drawThresholds(bench, win);
    if (section(win.check, "Re-run parameters")) drawRerun(bench, win);
    const bool tracked = win.mapping->mapper.poses == PoseSource::kTrack;
    if (tracked && section(win.check, "Tracking and loop closures", true)) drawTracking(bench, win);
    if (section(win.check, "View", true)) drawView(bench, win);
    if (!bench.staticMap() && section(win.check, "Mesh", bench.ui().settings.show_mesh)) drawMesh(bench, win);
    if (section(win.check, "Keyframes", true)) drawKeyframes(bench, mirror, win);
    if (section(win.check, "Picked ellipsoid", true)) drawPicked(bench, win);
    if (section(win.check, "Measure", bench.ui().measure_a.has_value())) drawMeasure(bench, win);
    if (section(win.check, "Queries", bench.ui().settings.probe || bench.ui().settings.query_slice))
      drawQueries(bench, win);
    if (section(win.check, "Pose correction")) drawPoseCorrection(bench);
    if (section(win.check, "Export and save")) drawExport(bench, win);
  }
  if (section(win.check, "Settings")) drawSettings(bench);
  ImGui::End();
}

}  // namespace vdmap::app::gui
