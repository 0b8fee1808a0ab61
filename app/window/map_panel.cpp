#include "app/window/map_panel.h"

#include <imgui_stdlib.h>

#include "app/window/keyframe_panel.h"
#include "app/window/measure_overlay.h"
#include "app/window/thresholds_panel.h"
#include "app/window/tracking_panel.h"
#include "app/window/view_tools_panel.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {
namespace {

void drawExport(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  if (beginRows("export")) {
    label(win.check, "folder", "Export writes what `vdmap map --out` writes into this folder (created if missing).");
    ImGui::InputText("##export", &ui.export_text);
    label(win.check, "session",
          "Save session writes one .vdmap file with keyframes, local maps and graph (vdmap gui FILE opens it).");
    ImGui::InputText("##session", &ui.session_text);
    ImGui::EndTable();
  }
  const std::string file = bench.staticMap() ? std::string("A map file: ") + kStaticMapWhy + "." : "";
  ImGui::BeginDisabled(ui.export_text.empty() || !file.empty());
  if (ImGui::Button("Export")) bench.files().exportMap();
  tip(!file.empty() ? file
      : ui.export_text.empty() ? "Type a folder above first." : "Writes the global map, local maps, poses and graph.");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(ui.session_text.empty() || !file.empty());
  if (ImGui::Button("Save session")) bench.files().saveSession();
  tip(!file.empty() ? file
      : ui.session_text.empty() ? "Type a file name above first." : "Writes the whole session to one .vdmap file.");
  ImGui::EndDisabled();
  checkFits(win.check);
}

}  // namespace

void drawMapPanel(Workbench& bench, const render::MapMirror& mirror, WindowState& win) {
  beginPanel("Map", win.layout.right, win.layout.right_w, win.layout.last_size.x);
  if (bench.isOpen()) {
    if (section(win.check, "Thresholds (live)", true)) drawThresholds(bench, win);
    if (section(win.check, "Re-run parameters")) drawRerun(bench, win);
    const bool tracked = win.mapping->mapper.poses == PoseSource::kTrack;
    if (tracked && section(win.check, "Tracking and loop closures", true)) drawTracking(bench, win);
    if (section(win.check, "View", true)) drawView(bench, win);
    if (section(win.check, "Keyframes", true)) drawKeyframes(bench, mirror, win);
    if (section(win.check, "Picked ellipsoid", true)) drawPicked(bench, win);
    if (section(win.check, "Measure", bench.ui().measure_a.has_value())) drawMeasure(bench, win);
    if (section(win.check, "Queries", bench.ui().probe || bench.ui().query_slice)) drawQueries(bench, win);
    if (section(win.check, "Pose correction")) drawPoseFile(bench);
    if (section(win.check, "Export and save")) drawExport(bench, win);
  }
  if (section(win.check, "Settings")) {
    if (ImGui::Button("Reset to defaults")) bench.parameters().resetToDefaults();
    tip("Thresholds, re-run parameters and view options back to the defaults; panels back to their widths.");
    const UiState& ui = bench.ui();
    ImGui::TextWrapped("This run started with: %s.", ui.settings_source.c_str());
    if (ui.settings_file.empty())
      ImGui::TextWrapped("Not saved on exit (a scripted run, or --settings): your settings are left as they are.");
    else
      ImGui::TextWrapped("Saved a second after each change and on exit (what you changed only) to %s; the window "
                         "layout to imgui.ini beside it.",
                         ui.settings_file.c_str());
  }
  ImGui::End();
}

}  // namespace vdmap::app::gui
