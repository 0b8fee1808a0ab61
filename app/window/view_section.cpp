// The Map panel's "View" section: colour, shape, up axis, layers, the height slice, framing,
// the screenshot, view files and the `vdmap render` command of the view.
#include <cfloat>
#include <ctime>
#include <filesystem>
#include <string>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "app/view/view_file.h"
#include "app/window/map_sections.h"
#include "app/window/widgets.h"
#include "render/colormap.h"

namespace vdmap::app::gui {
namespace {

// A modal "FILE exists. Replace it?" while `file` is set: true when Replace is clicked; either
// button clears `file`.
bool askToReplace(const char* title, std::string& file) {
  if (file.empty()) return false;
  ImGui::OpenPopup(title);
  bool replace = false;
  if (ImGui::BeginPopupModal(title, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s exists. Replace it?", file.c_str());
    replace = ImGui::Button("Replace");
    ImGui::SameLine();
    if (replace || ImGui::Button("Cancel")) {
      file.clear();
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
  return replace;
}

// The Screenshot row: the window or the 3-D view alone, to the name typed or a timestamped one
// in ~/Pictures/vdmap; a typed name that exists asks before it is replaced.
void drawScreenshot(WindowState& win) {
  const auto request = [&win](const std::string& file) {
    win.screenshot_request = file;
    win.screenshot_request_view = win.screenshot_view_only;
  };
  if (ImGui::Button("Screenshot")) {
    std::error_code ignored;
    if (win.screenshot_text.empty()) request(defaultScreenshotFile(std::time(nullptr)).string());
    else if (std::filesystem::exists(win.screenshot_text, ignored)) win.screenshot_confirm = win.screenshot_text;
    else request(win.screenshot_text);
  }
  tip("Writes a PNG of the " + std::string(win.screenshot_view_only ? "3-D view alone (no panels)" : "whole window") +
      " to the file named on the right, or (none typed) to a new timestamped file in " +
      (screenshotFolder().empty() ? std::string("the working folder") : screenshotFolder().string()) +
      ". An existing file is never replaced without asking; the status line gives the path.");
  ImGui::SameLine();
  const char* kinds[] = {"window", "3-D view"};
  int kind = win.screenshot_view_only ? 1 : 0;
  ImGui::SetNextItemWidth(ImGui::CalcTextSize("3-D view").x + 2.5f * ImGui::GetFrameHeight());
  if (ImGui::Combo("##shotkind", &kind, kinds, 2)) win.screenshot_view_only = kind == 1;
  tip("What the screenshot shows: the whole window, or the 3-D view alone at its size.");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-FLT_MIN);
  ImGui::InputTextWithHint("##shot", "vdmap-YYYYMMDD-HHMMSS.png", &win.screenshot_text);
  tip("The PNG file; empty: a timestamped name in the screenshot folder.");
  checkFits(win.check);
  const std::string file = win.screenshot_confirm;
  if (askToReplace("Replace screenshot?", win.screenshot_confirm)) request(file);
}

// The height slice: "Slice" on/off, its heights above the floor (m), and "Frame slice". The
// same slice as `vdmap render --slice` (settings keys slice, slice_lo, slice_hi); PgUp / PgDn
// move it by its thickness.
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
  if (ImGui::DragFloatRange2("##slice", &lo, &hi, 0.01f, -100.f, 100.f, "%.2f m", "%.2f m",
                             ImGuiSliderFlags_AlwaysClamp) &&
      lo < hi) {
    slice.lo_m = lo;
    slice.hi_m = hi;
  }
  tip("Heights above the floor, metres: from, to.");
  ImGui::EndDisabled();
  checkFits(win.check);
  ImGui::BeginDisabled(!slice.on);
  if (ImGui::Button("Frame slice")) bench.view().frameMap();  // frameMap frames what is drawn: the slice
  tip("Fits what the slice keeps in the view (F frames the same while the slice is on).");
  ImGui::EndDisabled();
  checkFits(win.check);
}

}  // namespace

void drawView(Workbench& bench, WindowState& win) {
  Settings& s = bench.ui().settings;
  if (beginRows("view")) {
    label(win.check, "colour",
          "rgb: the surface colour; keyframe: the keyframe each ellipsoid came from (the key in the view); "
          "uncertainty: the largest standard deviation; count: points merged into it; height: height above the "
          "floor along the up axis, over the slice when it is on (colour bars in the view).");
    int color = static_cast<int>(s.color);
    if (ImGui::Combo("##colour", &color, render::kColorModeNames.data(),
                     static_cast<int>(render::kColorModeNames.size())))
      s.color = static_cast<render::ColorMode>(color);
    label(win.check, "draw",
          "Ellipsoids as surfaces at sigma standard deviations, their centres as points (faster), or hidden: no map, "
          "the trajectories and cameras alone (not remembered: the next run shows the map).");
    int shape = s.hide_map ? 2 : s.show_ellipsoids ? 0 : 1;
    const char* shapes[] = {"ellipsoids", "centres", "hidden"};
    if (ImGui::Combo("##shape", &shape, shapes, 3)) {
      s.hide_map = shape == 2;
      if (shape < 2) s.show_ellipsoids = shape == 0;
    }
    label(win.check, "sigma", "Ellipsoid surfaces drawn at this many standard deviations.");
    ImGui::BeginDisabled(!s.show_ellipsoids || s.hide_map);
    ImGui::SliderFloat("##sigma", &s.ellipsoid_sigma, 0.5f, 4.f, "%.1f");
    tip(s.hide_map ? "The map is hidden." : s.show_ellipsoids ? "" : "Only the centres are drawn.");
    ImGui::EndDisabled();
    label(win.check, "up axis",
          "The world direction kept up on screen, the one the view orbits about. data: estimated from the "
          "cameras (their mean image-up direction) refined by the floor's normals; for a map file without cameras, "
          "from its level planes (floors, tables) and walls.");
    // The four axes, and "custom": a direction the user sets (first the one shown).
    const char* ups[] = {kUpAxisNames[0], kUpAxisNames[1], kUpAxisNames[2], kUpAxisNames[3], "custom"};
    int up = s.up_vector ? 4 : static_cast<int>(s.up_axis);
    if (ImGui::Combo("##up", &up, ups, 5)) {
      if (up == 4) s.up_vector = bench.view().upVector();
      else s.up_axis = static_cast<UpAxis>(up), s.up_vector.reset();
      bench.view().resetView();
    }
    if (s.up_vector) {
      label(win.check, "up x,y,z", "The custom up direction (world frame); the view orbits about it.");
      glm::vec3 v = *s.up_vector;
      if (ImGui::DragFloat3("##upvec", &v.x, 0.01f, -1.f, 1.f, "%.2f") && glm::length(v) > 1e-3f) {
        s.up_vector = v;
        bench.view().resetView();
      }
      if (ImGui::Button("up from view")) {
        s.up_vector = bench.ui().camera.imageUp();
        bench.view().resetView();
      }
      tip("Makes the direction up on the screen now the up direction: turn the view with the trackball until the "
          "room stands upright, then press this.");
    }
    label(win.check, "projection", "perspective, or orthographic: parallel rays, no vanishing lines.");
    int projection = static_cast<int>(s.projection);
    if (ImGui::Combo("##projection", &projection, render::kProjectionNames, 2))
      bench.view().setProjection(static_cast<render::Projection>(projection));
    label(win.check, "rotation",
          "How a drag turns the view: orbit about the up axis (the horizon stays level), or trackball (free "
          "rotation about the screen's axes; the view may roll).");
    int rotation = static_cast<int>(s.rotation);
    if (ImGui::Combo("##rotation", &rotation, render::kRotationNames, 2))
      bench.view().setRotation(static_cast<render::Rotation>(rotation));
    label(win.check, "preset", "Views along the map's walls: from above, from the front, from the side.");
    for (int i = 0; i < 3; ++i) {
      if (i > 0) ImGui::SameLine();
      if (ImGui::Button(render::kViewPresetNames[i])) bench.view().preset(static_cast<render::ViewPreset>(i));
    }
    label(win.check, "show",
          "Keyframe frustums (yellow: current, white: selected, red: the camera now), covisibility edges "
          "(viridis by weight) and the camera trajectory (blue).");
    ImGui::Checkbox("frustums", &s.show_frustums);
    ImGui::SameLine();
    ImGui::Checkbox("graph", &s.show_graph);
    ImGui::SameLine();
    ImGui::Checkbox("trajectory", &s.show_trajectory);
    checkFits(win.check);
    label(win.check, "mesh",
          "The surface mesh of the local maps (docs/method.md 14), built with every global map while it is on "
          "(a threshold or pose edit re-meshes): shaded grey, in its colours, or its triangles' edges. The "
          "ellipsoids lie on it and would cover it, so turning it on sets draw to hidden and turning it off brings "
          "them back; set draw to ellipsoids to see both. A map file has no local maps, so no mesh.");
    ImGui::Checkbox("##mesh", &s.show_mesh);
    ImGui::SameLine();
    int mesh_style = static_cast<int>(s.mesh_style);
    ImGui::BeginDisabled(!s.show_mesh);
    if (ImGui::Combo("##mesh_style", &mesh_style, render::kMeshStyleNames, 3))
      s.mesh_style = static_cast<render::MeshStyle>(mesh_style);
    ImGui::EndDisabled();
    ImGui::EndTable();
  }
  drawSliceControls(bench, win);
  if (ImGui::Button("Frame map (F)")) bench.view().frameMap();
  tip("Fits the map in the view, keeping the direction; the view follows the map again as it grows.");
  ImGui::SameLine();
  if (ImGui::Button("Frame paths (T)")) bench.view().frameTrajectories();
  tip("Fits the tracked trajectory (and the ground truth, when shown) in the view, not the map.");
  checkFits(win.check);
  if (ImGui::Button("Reset view (R)")) bench.view().resetView();
  tip("The default view of the whole map from above, about the up axis; follows the map again.");
  ImGui::SameLine();
  if (ImGui::Button("Help (H)")) bench.key(KeyAction::kHelp);
  checkFits(win.check);
  drawScreenshot(win);
  // The view as a view file, and the command that draws it headless (docs/workbench.md "Save view").
  UiState& ui = bench.ui();
  ImGui::BeginDisabled(ui.view_file_text.empty());
  if (ImGui::Button("Save view (Ctrl+S)")) bench.viewFiles().saveSafely(ui.view_file_text);
  tip(ui.view_file_text.empty()
          ? "Type a file name on the right first."
          : "Writes the view shown (camera, size, colours, layers, thresholds) as a view file to the "
            "file named on the right; `vdmap render --view-file` draws the same picture. The status "
            "line gives the command. The default name numbers itself (vdmap_view-2.json ...); "
            "another name that exists asks first.");
  checkFits(win.check);
  ImGui::SameLine();
  if (ImGui::Button("Load view")) bench.viewFiles().load(ui.view_file_text, ui.load_view_thresholds);
  tip("Shows the view file named on the right: its camera and view options (the window keeps its own size; a "
      "different size is named in the status line)" +
      std::string(ui.load_view_thresholds ? ", and its thresholds." : "; its thresholds only when ticked below."));
  checkFits(win.check);
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-FLT_MIN);
  ImGui::InputText("##viewfile", &ui.view_file_text);
  ImGui::Checkbox("Load view: also its thresholds", &ui.load_view_thresholds);
  tip("Off: Load view changes the view alone (as --view-file); on: the file's thresholds are applied too (as --settings).");
  const std::string view_file = ui.confirm_view_replace;
  if (askToReplace("Replace view file?", ui.confirm_view_replace)) bench.viewFiles().saveSafely(view_file, true);
  std::string command = renderCommand(bench.view().spec(), bench.viewFiles().commandSource());
  if (ImGui::Button("Copy")) ImGui::SetClipboardText(command.c_str());
  tip("Copies the `vdmap render` command that draws this view (every option spelled out) to the clipboard.");
  checkFits(win.check);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-FLT_MIN);
  ImGui::InputText("##command", &command, ImGuiInputTextFlags_ReadOnly);
  tip(command);
}

}  // namespace vdmap::app::gui
