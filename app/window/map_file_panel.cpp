#include "app/window/map_file_panel.h"

#include <filesystem>

#include <imgui.h>
#include <imgui_stdlib.h>
#include <nlohmann/json.hpp>

#include "app/window/widgets.h"
#include "mapping/core/message_text.h"

namespace vdmap::app::gui {

void drawOpenArea(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  const ImGuiStyle& style = ImGui::GetStyle();
  const float open_w = ImGui::CalcTextSize("Open").x + 2 * style.FramePadding.x;
  const float browse_w = ImGui::CalcTextSize("...").x + 2 * style.FramePadding.x;
  const float recent_w = ImGui::GetFrameHeight();
  ImGui::SetNextItemWidth(-open_w - browse_w - recent_w - 3 * style.ItemSpacing.x);
  const bool enter = ImGui::InputText("##folder", &ui.sequence_text, ImGuiInputTextFlags_EnterReturnsTrue);
  tip("A TUM RGB-D folder (rgb.txt), a saved session (.vdmap), a `vdmap map` folder, an ellipsoid or point PLY, an "
      "OctoMap (.bt, .ot) or a view file (.json: applied to the view). Files can also be dropped on the window.");
  ImGui::SameLine();
  ImGui::BeginDisabled(ui.sequence_text.empty());
  if (ImGui::Button("Open") || (enter && !ui.sequence_text.empty())) bench.files().openPath(ui.sequence_text);
  tip(ui.sequence_text.empty() ? "Type a path on the left first (or drop a file on the window)."
                               : "Opens what the path on the left holds; errors show in the status line below.");
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("...")) openFileBrowser(win.browser, ui.sequence_text);
  tip("Browse: folders first, what each entry opens as; a sequence or map folder opens as a whole.");
  ImGui::SameLine();
  ImGui::BeginDisabled(ui.settings.recent.empty());
  if (ImGui::BeginCombo("##recent", "", ImGuiComboFlags_NoPreview | ImGuiComboFlags_PopupAlignLeft)) {
    std::string chosen;
    for (const std::string& path : ui.settings.recent) {
      std::error_code ec;
      const bool there = std::filesystem::exists(path, ec);
      if (!there) ImGui::PushStyleColor(ImGuiCol_Text, style.Colors[ImGuiCol_TextDisabled]);
      if (ImGui::Selectable(path.c_str())) chosen = path;
      if (!there) {
        ImGui::PopStyleColor();
        tip("No longer there.");
      }
    }
    ImGui::EndCombo();
    if (!chosen.empty()) {
      ui.sequence_text = chosen;
      bench.files().openPath(chosen);
    }
  }
  tip(ui.settings.recent.empty() ? "Nothing opened yet: the paths opened go here." : "Recently opened, newest first.");
  ImGui::EndDisabled();
  if (const std::string chosen = drawFileBrowser(win.browser, win.double_click); !chosen.empty()) {
    ui.sequence_text = chosen;
    bench.files().openPath(chosen);
  }
}

void drawStaticMapFigures(const Workbench& bench, WindowState& win) {
  const StaticMap* m = bench.staticMap();
  if (!m) return;
  ImGui::TextWrapped("%s: %s.", mapFileKindName(m->kind), kStaticMapWhy);
  if (beginRows("map file")) {
    const auto row = [&](const char* name, const std::string& help, const std::string& value) {
      label(win.check, name, help);
      ImGui::TextUnformatted(value.c_str());
    };
    row("ellipsoids",
        "Drawn from the file: a PLY's vertices, a map folder's global_ellipsoids.ply, or an OctoMap's "
        "occupied leaves (each a cube's covariance, size^2/12).",
        std::to_string(m->ellipsoids.size()));
    if (m->kind == MapFileKind::kPointPly)
      row("point sigma",
          "Each point drawn as a sphere of this standard deviation: half the median distance to the "
          "nearest point.",
          metres(m->sigma_m));
    if (m->kind == MapFileKind::kOctomap)
      row("resolution", "The OctoMap's finest voxel size; pruned leaves are 2^k voxels wide.", metres(m->sigma_m));
    if (m->kind == MapFileKind::kMapFolder) {
      row("keyframes", "keyframes.txt: the keyframe poses (drawn as frustums with the TUM camera's shape).",
          std::to_string(m->keyframes.size()));
      row("edges", "graph.txt: covisibility edges.", std::to_string(m->edges.size()));
      row("trajectory", "trajectory.txt: the mapped frames' poses (when the map was exported with them).",
          counted(static_cast<long long>(m->trajectory.size()), "pose"));
      const nlohmann::json stats = nlohmann::json::parse(m->stats_json, nullptr, false);
      if (stats.is_object())
        for (const char* key : {"frames", "sigma_e", "sigma_e_prime", "t_g_s"})
          if (stats.contains(key) && stats.at(key).is_number())
            row(key, std::string("stats.json: ") + key + " of the `vdmap map` run that wrote the folder.",
                stats.at(key).dump());
    }
    ImGui::EndTable();
  }
  checkFits(win.check);
}

}  // namespace vdmap::app::gui
