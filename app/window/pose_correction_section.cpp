// The Map panel's "Pose correction" section: a corrected TUM trajectory whose poses the
// keyframes it names take.
#include <cfloat>
#include <string>

#include <imgui_stdlib.h>

#include "app/window/map_sections.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {

void drawPoseCorrection(Workbench& bench) {
  UiState& ui = bench.ui();
  ImGui::SetNextItemWidth(-FLT_MIN);
  ImGui::InputTextWithHint("##trajectory", "corrected TUM trajectory file", &ui.trajectory_text);
  tip("A TUM trajectory (timestamp tx ty tz qx qy qz qw): keyframes whose timestamps it names take its poses.");
  const bool file = bench.staticMap() != nullptr;  // opening files: nothing to rebuild
  ImGui::BeginDisabled(ui.trajectory_text.empty() || file);
  if (ImGui::Button("Load corrected trajectory")) bench.files().loadTrajectory();
  tip(file                         ? std::string("A map file: ") + kStaticMapWhy + "."
      : ui.trajectory_text.empty() ? "Type the trajectory file's path above first."
                                   : "Replaces the matching keyframes' poses; the map is rebuilt.");
  ImGui::EndDisabled();
}

}  // namespace vdmap::app::gui
