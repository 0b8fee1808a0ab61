// The Map panel's "Queries" section (docs/workbench.md "Queries"): the probe and the query slice.
#include <algorithm>

#include <imgui.h>

#include "app/window/map_sections.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {

void drawQueries(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  const auto query = bench.queries().snapshot();
  ImGui::Checkbox("Probe (Q)", &ui.settings.probe);
  tip("Under the cursor: occupied, free or unknown (docs/method.md 13) with p_occupied, and the distance to the "
      "nearest surface, beside the cursor and in the status line. The point stands the offset in front of the "
      "surface under the cursor (Alt+wheel changes it), or on the query slice while it is shown.");
  checkFits(win.check);
  if (beginRows("queries")) {
    label(win.check, "probe offset",
          "How far in front of the surface under the cursor (toward the eye) the probe stands.");
    ImGui::DragFloat("##probe_offset", &ui.settings.probe_offset_m, 0.002f, 0.f, 1.f, "%.3f m",
                     ImGuiSliderFlags_AlwaysClamp);
    ImGui::EndTable();
  }
  if (ui.settings.probe && ui.probe_result) ImGui::TextWrapped("%s", ui.probe_result->text().c_str());
  ImGui::Checkbox("Query slice", &ui.settings.query_slice);
  tip("A plane through the map coloured by the queries at its samples: free green, occupied red, unknown grey "
      "(or the distance to the nearest surface), over the box the keyframes see. Unlike the height slice (View), "
      "which keeps the ellipsoids between two heights, it draws what the map answers, in the free space too.");
  checkFits(win.check);
  render::QuerySliceSpec& spec = ui.settings.query_slice_spec;
  ImGui::BeginDisabled(!ui.settings.query_slice);
  if (beginRows("query_slice")) {
    label(win.check, "axis",
          "The plane's normal: the map's up axis (offset = height above the floor, as the height "
          "slice measures), or a world axis (offset = that coordinate).");
    int axis = static_cast<int>(spec.axis);
    if (ImGui::Combo("##qs_axis", &axis, "up\0x\0y\0z\0")) spec.axis = static_cast<render::QuerySliceAxis>(axis);
    label(win.check, "offset", "Where the plane lies along its axis, metres.");
    float offset = static_cast<float>(spec.offset_m);
    if (ImGui::DragFloat("##qs_offset", &offset, 0.01f, -100.f, 100.f, "%.2f m")) spec.offset_m = offset;
    label(win.check, "colour",
          "occupancy: free green, occupied red, unknown grey; distance: viridis from 0 (dark) "
          "to the max distance (yellow), unknown grey.");
    int color = static_cast<int>(spec.color);
    if (ImGui::Combo("##qs_color", &color, "occupancy\0distance\0"))
      spec.color = static_cast<render::QuerySliceColor>(color);
    if (spec.color == render::QuerySliceColor::kDistance) {
      label(win.check, "max distance", "The distance the colour ramp ends at (yellow), metres.");
      float max_m = static_cast<float>(spec.max_distance_m);
      if (ImGui::DragFloat("##qs_max", &max_m, 0.01f, 0.01f, 10.f, "%.2f m", ImGuiSliderFlags_AlwaysClamp))
        spec.max_distance_m = max_m;
    }
    label(win.check, "samples", "Samples along the plane's longer side.");
    ImGui::SliderInt("##qs_samples", &spec.samples, 32, 1024, "%d", ImGuiSliderFlags_AlwaysClamp);
    ImGui::EndTable();
  }
  ImGui::EndDisabled();
  if (const auto slice = bench.queries().slice()) {
    const double n = std::max<double>(1.0, static_cast<double>(slice->occupied + slice->free + slice->unknown));
    ImGui::TextWrapped("%dx%d samples in %.0f ms: %.0f%% occupied, %.0f%% free, %.0f%% unknown", slice->plane.width,
                       slice->plane.height, slice->compute_ms, 100.0 * slice->occupied / n, 100.0 * slice->free / n,
                       100.0 * slice->unknown / n);
  }
  if (query) {
    ImGui::TextDisabled("queries of map %d, built in %.0f ms%s%s", query->generation, query->build_ms,
                        query->note.empty() ? "" : "; ", query->note.c_str());
  } else if (ui.settings.probe || ui.settings.query_slice) {
    ImGui::TextDisabled("building the queries...");
  }
}

}  // namespace vdmap::app::gui
