// The Map panel's "Keyframes" section: the keyframe list, the selected keyframe's inspector
// (figures, container view, neighbours) and its pose edit.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>

#include "app/window/map_sections.h"
#include "app/window/widgets.h"
#include "mapping/core/message_text.h"
#include "render/colormap.h"

namespace vdmap::app::gui {
namespace {

// The last item (a pose field) starts a drag: remember the pose for undo.
void poseEditStarted(Workbench& bench) {
  if (ImGui::IsItemActivated()) bench.poses().beginEdit();
}

// Every keyframe, its colour as a square; a click selects it.
void drawKeyframeList(Workbench& bench, const WindowState& win) {
  // A keyframe picked in the view or by a loop marker scrolls into the list's middle once.
  const bool scroll = bench.poses().takeScrollToSelected();
  if (ImGui::BeginListBox("##keyframes", {-FLT_MIN, ImGui::GetTextLineHeightWithSpacing() * 6.5f})) {
    for (const KeyframeInfo& k : win.mapping->keyframes) {
      char text[96];
      std::snprintf(text, sizeof text, "   K%d  frame %d  %s%s", k.id, k.frame,
                    counted(static_cast<long long>(k.ellipsoids), "cell").c_str(),
                    k.id == win.mapping->current_keyframe ? "  (current)" : "");
      const ImVec2 at = ImGui::GetCursorScreenPos();
      if (ImGui::Selectable(text, k.id == bench.ui().selected_keyframe)) bench.poses().selectKeyframe(k.id);
      if (scroll && k.id == bench.ui().selected_keyframe) ImGui::SetScrollHereY(0.5f);
      const float h = ImGui::GetTextLineHeight();
      ImGui::GetWindowDrawList()->AddRectFilled({at.x + 2, at.y + 2}, {at.x + h - 2, at.y + h - 2},
                                                rgbColor(render::keyframeColor(k.id)));
    }
    ImGui::EndListBox();
  }
  tip("Keyframes with the frame that created them and their container cells; the square is the keyframe's colour "
      "(colour mode \"keyframe\"). Click to inspect.");
}

// Keyframe `id`'s figures, container view, neighbours and view buttons.
void drawInspector(Workbench& bench, const render::MapMirror& mirror, WindowState& win, int id) {
  UiState& ui = bench.ui();
  const KeyframeInfo& k = win.mapping->keyframes[static_cast<std::size_t>(id)];
  std::size_t kept = 0;
  if (win.global && id < static_cast<int>(win.global->map.kept.size())) {
    const std::vector<bool>& cells = win.global->map.kept[static_cast<std::size_t>(id)];
    kept = static_cast<std::size_t>(std::count(cells.begin(), cells.end(), true));
  }
  ImGui::TextWrapped("K%d: %s, %zu kept by the filter, %s integrated", id,
                     counted(static_cast<long long>(k.ellipsoids), "ellipsoid").c_str(), kept,
                     counted(k.frames_integrated, "frame").c_str());
  tip("Its local map: one ellipsoid per touched container cell (docs/method.md 2); of those, the ones the filter keeps with "
      "the live thresholds (min points, k; docs/method.md 4); and the frames whose depth went into it.");
  const render::Texture2D& container = mirror.containerTexture();
  if (!mirror.containerImage().empty()) {
    const float w = ImGui::GetContentRegionAvail().x;
    ImGui::Image(textureId(container), {w, w * container.height() / std::max(1, container.width())});
    tip("The container view (paper Fig. 1): the keyframe's image in the middle of its 2W x 2H container with its "
        "kept ellipsoids projected as 2-sigma ellipses. Click to enlarge.");
    if (ImGui::IsItemClicked()) ui.show_container = true;
  }
  std::string neighbours;
  for (const CovisibilityEdge& e : win.mapping->edges)
    if (e.a == id || e.b == id) {
      char item[32];
      std::snprintf(item, sizeof item, "K%d (%.2f) ", e.a == id ? e.b : e.a, e.weight);
      neighbours += item;
    }
  ImGui::TextWrapped("neighbours (edge weight): %s", neighbours.empty() ? "none" : neighbours.c_str());
  tip("Covisibility edges: the share of features one keyframe re-observes of the other (docs/method.md 5).");
  if (ImGui::Button("View from keyframe")) ui.view_from_keyframe = id;
  tip("Looks through the keyframe with its own intrinsics (its image's aspect kept; Esc or a drag leaves).");
  ImGui::SameLine();
  if (ImGui::Button("Container view")) ui.show_container = true;
  tip("A larger container view with zoom, cell grid and image bounds.");
  checkFits(win.check);
}

// The selected keyframe's pose as translation and roll, pitch, yaw: a drag sends it; undo.
void drawPoseEdit(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  ImGui::TextUnformatted("pose T_W_K (drag to correct):");
  bool moved = false;
  const bool before = ui.show_before_optimisation;
  ImGui::BeginDisabled(before);
  // A pixel of drag moves the keyframe as far as a pixel of the view spans at its depth.
  const float speed = bench.view().poseDragSpeed();
  if (beginRows("pose")) {
    label(
        win.check, "t (m)",
        "The keyframe's position in the world, metres. Dragging moves its whole local map; the global map is rebuilt. "
        "A pixel of drag moves it " +
            metres(speed) +
            " (what a pixel of the view spans at the keyframe's depth); "
            "hold Alt for 100x finer, Shift for 10x coarser (Dear ImGui's drag keys); double-click to type a value.");
    moved |= ImGui::DragFloat3("##t", &ui.pose_translation_m.x, speed, -1000.f, 1000.f, "%.3f");
    poseEditStarted(bench);
    label(win.check, "roll, pitch, yaw (deg)",
          "R = Rz(yaw) Ry(pitch) Rx(roll); pitch stays within +-90 degrees. 0.2 degrees per pixel of drag; Alt: 100x "
          "finer, Shift: 10x coarser.");
    glm::vec3& rpy = ui.pose_rotation_deg;
    moved |= ImGui::DragFloat3("##rpy", &rpy.x, 0.2f, 0.f, 0.f, "%.1f");
    poseEditStarted(bench);
    ImGui::EndTable();
    // Roll and yaw wrap around; pitch stops at +-90 (beyond it the same rotation has other angles).
    for (float* a : {&rpy.x, &rpy.z}) *a = *a - 360.f * std::round(*a / 360.f);
    rpy.y = std::clamp(rpy.y, -90.f, 90.f);
  }
  ImGui::EndDisabled();
  if (before) tip("Showing the map before the last optimisation: poses are edited on the map after it (B).");
  if (moved) bench.poses().applyEdit();
  ImGui::BeginDisabled(!bench.poses().canUndoEdit());
  if (ImGui::Button("Undo pose edit (Ctrl+Z)")) bench.poses().undoEdit();
  tip(bench.poses().canUndoEdit() ? "Puts back the pose from before the last drag." : "No pose edit to undo.");
  ImGui::EndDisabled();
}

}  // namespace

void drawKeyframes(Workbench& bench, const render::MapMirror& mirror, WindowState& win) {
  if (win.mapping->keyframes.empty()) return ImGui::TextUnformatted("no keyframes yet");
  drawKeyframeList(bench, win);
  const int id = bench.ui().selected_keyframe;
  if (id < 0 || id >= static_cast<int>(win.mapping->keyframes.size()))
    return ImGui::TextWrapped("Select a keyframe to inspect it.");
  if (bench.staticMap()) {  // opening files: a map file's keyframes are poses only
    ImGui::TextDisabled("K%d: no inspector, container or pose edit", id);
    return tip(std::string("A map file: ") + kStaticMapWhy + ".");
  }
  drawInspector(bench, mirror, win, id);
  drawPoseEdit(bench, win);
}

}  // namespace vdmap::app::gui
