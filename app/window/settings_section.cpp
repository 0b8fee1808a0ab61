// The Map panel's "Settings" section: back to the defaults, and which settings this run started
// with and where they are saved.
#include "app/window/map_sections.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {

void drawSettings(Workbench& bench) {
  if (ImGui::Button("Reset to defaults")) bench.parameters().resetToDefaults();
  tip("Thresholds, re-run parameters and view options back to the defaults; panels back to their widths.");
  const UiState& ui = bench.ui();
  textWrapped("This run started with: " + ui.settings_source + ".");
  if (ui.settings_file.empty())
    ImGui::TextWrapped("Not saved on exit (a scripted run, or --settings): your settings are left as they are.");
  else
    textWrapped("Saved a second after each change and on exit (what you changed only) to " + ui.settings_file +
                "; the window layout to imgui.ini and quick views to quick_views/ beside it.");
}

}  // namespace vdmap::app::gui
