// The Map panel's "Export and save" section: what `vdmap map --out` writes, and the session file.
#include <string>

#include <imgui_stdlib.h>

#include "app/window/map_sections.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {

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
  tip(!file.empty()            ? file
      : ui.export_text.empty() ? "Type a folder above first."
                               : "Writes the global map, local maps, poses and graph.");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(ui.session_text.empty() || !file.empty());
  if (ImGui::Button("Save session")) bench.files().saveSession();
  tip(!file.empty()             ? file
      : ui.session_text.empty() ? "Type a file name above first."
                                : "Writes the whole session to one .vdmap file.");
  ImGui::EndDisabled();
  checkFits(win.check);
}

}  // namespace vdmap::app::gui
