// The Map panel's "Measure" section: the points measured with Ctrl+click in the view
// (measure_overlay.cpp), their distance, Copy, Clear and snapping.
#include <cstdio>
#include <string>

#include "app/window/map_sections.h"
#include "app/window/measure_overlay.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {
namespace {

// "x y z" (metres), as Copy writes it.
std::string pointText(const glm::vec3& p) {
  char text[96];
  std::snprintf(text, sizeof text, "%.4f %.4f %.4f", p.x, p.y, p.z);
  return text;
}

}  // namespace

void drawMeasure(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  if (!ui.measure_a) ImGui::TextWrapped("Ctrl+click a surface in the view for point A, then for B.");
  if (ui.measure_a && beginRows("measure")) {
    label(win.check, "A (m)", "The first point: the surface drawn under the cursor (world frame, metres).");
    ImGui::TextUnformatted(pointText(*ui.measure_a).c_str());
    label(win.check, "B (m)", "The second point; the next Ctrl+click starts again at A.");
    ImGui::TextUnformatted(ui.measure_b ? pointText(*ui.measure_b).c_str() : "Ctrl+click for B");
    if (ui.measure_b) {
      label(win.check, "distance", "|B - A| and its components along the world axes x, y, z.");
      ImGui::TextUnformatted(distanceText(*ui.measure_a, *ui.measure_b).c_str());
    }
    ImGui::EndTable();
  }
  ImGui::BeginDisabled(!ui.measure_a);
  if (ImGui::Button("Copy##measure")) {
    std::string text = pointText(*ui.measure_a) + "\n";
    if (ui.measure_b) text += pointText(*ui.measure_b) + "\n";
    ImGui::SetClipboardText(text.c_str());
  }
  tip(ui.measure_a ? "Copies the points as \"x y z\" lines (metres) to the clipboard." : "Nothing measured yet.");
  ImGui::SameLine();
  if (ImGui::Button("Clear##measure")) ui.measure_a.reset(), ui.measure_b.reset();
  tip("Forgets both points.");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::Checkbox("snap to ellipsoid centres", &ui.measure_snap);
  tip("Measured points move to the nearest ellipsoid centre of the global map (its mean) instead of the drawn "
      "surface under the cursor.");
  checkFits(win.check);
}

}  // namespace vdmap::app::gui
