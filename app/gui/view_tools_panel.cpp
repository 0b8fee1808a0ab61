#include "app/gui/view_tools_panel.h"

#include <imgui.h>

#include "app/gui/widgets.h"

namespace vdmap::app::gui {

void drawSliceControls(Workbench& bench, WindowState& win) {
  render::HeightSlice& slice = bench.ui().settings.slice;
  ImGui::Checkbox("Slice", &slice.on);
  tip("Draw only the ellipsoids whose centre lies between these heights above the floor (the 2nd percentile of "
      "the map's heights along the up axis), whole; picking and framing ignore the rest. PgUp / PgDn move the "
      "slice by its thickness.");
  ImGui::SameLine();
  // DragFloatRange2 places its (empty) label one inner spacing after the fields: leave room.
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - ImGui::GetStyle().ItemInnerSpacing.x);
  ImGui::BeginDisabled(!slice.on);
  float lo = slice.lo_m, hi = slice.hi_m;
  if (ImGui::DragFloatRange2("##slice", &lo, &hi, 0.01f, -100.f, 100.f, "%.2f m", "%.2f m", ImGuiSliderFlags_AlwaysClamp) &&
      lo < hi) {
    slice.lo_m = lo;
    slice.hi_m = hi;
  }
  tip("Heights above the floor, metres: from, to.");
  ImGui::EndDisabled();
  checkFits(win.check);
  ImGui::BeginDisabled(!slice.on);
  if (ImGui::Button("Frame slice")) bench.frameMap();  // frameMap frames what is drawn: the slice
  tip("Fits what the slice keeps in the view (F frames the same while the slice is on).");
  ImGui::EndDisabled();
  checkFits(win.check);
}

}  // namespace vdmap::app::gui
