#include "app/window/thresholds_panel.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <vector>

#include <imgui_stdlib.h>

#include "app/window/tg_parts.h"
#include "app/window/map_file_panel.h"
#include "app/window/view_tools_panel.h"  // the height slice
#include "app/window/widgets.h"
#include "app/view/view_file.h"
#include "render/colormap.h"

namespace vdmap::app::gui {
namespace {

// One parameter of the table as a slider, combo or checkbox; disabled, saying why, unless
// why_disabled is "".
void parameterRow(Workbench& bench, WindowState& win, const Parameter& p, const std::string& why_disabled) {
  const bool disabled = !why_disabled.empty();
  const bool pending = bench.parameters().pending(p);
  std::string help = std::string(p.help) + "\n\nvalid: " + validityText(p) + "; `vdmap map " + std::string(p.flag) +
                     "`, --set / settings.json " + (p.live ? "thresholds." : "rerun.") + std::string(p.key) + ".";
  if (pending)
    help += "\n\nPending: the map shown was made with " + formatValue(p, bench.parameters().inUse(p)) +
            (p.live ? " (rebuilding)." : "; Re-run applies the edited value.");
  if (disabled) help = why_disabled + "\n\n" + help;
  const std::string text =
      std::string(p.label) + (p.unit.empty() ? "" : " (" + std::string(p.unit) + ")") + (pending ? " *" : "");
  label(win.check, text.c_str(), help, pending);
  ImGui::BeginDisabled(disabled);
  double v = p.get(bench.ui().params);
  bool changed = false;
  const std::string id = "##" + std::string(p.key);
  switch (p.kind) {
    case Parameter::Kind::kBool: {
      bool b = v != 0;
      changed = ImGui::Checkbox(id.c_str(), &b);
      v = b;
      break;
    }
    case Parameter::Kind::kChoice: {
      int i = static_cast<int>(v);
      std::vector<const char*> names(p.choices.begin(), p.choices.end());
      changed = ImGui::Combo(id.c_str(), &i, names.data(), static_cast<int>(names.size()));
      v = i;
      break;
    }
    case Parameter::Kind::kInt:
    case Parameter::Kind::kReal: {
      const char* format = p.kind == Parameter::Kind::kInt ? "%.0f" : "%.3g";
      changed = ImGui::SliderScalar(id.c_str(), ImGuiDataType_Double, &v, &p.slider_lo, &p.slider_hi, format);
      if (p.kind == Parameter::Kind::kInt) v = std::round(v);
      break;
    }
  }
  tip(help);
  ImGui::EndDisabled();
  if (changed) bench.parameters().edit(p, v);
}

// The global map's figures (docs/method.md 6.4) under the thresholds, and a warning when the filter keeps
// few of the local maps' ellipsoids.
void drawMapFigures(Workbench& bench, WindowState& win) {
  const GlobalMap& m = win.global->map;
  std::size_t stored = 0;
  for (const KeyframeInfo& k : win.mapping->keyframes) stored += k.ellipsoids;
  if (beginRows("stats")) {
    const auto row = [&](const char* name, const std::string& help, const char* format, auto... values) {
      label(win.check, name, help);
      ImGui::Text(format, values...);
    };
    row("local maps", "Ellipsoids stored in all keyframes' containers (one per touched cell), before filtering.", "%zu",
        stored);
    row("Sigma_e", "Sigma_e (docs/method.md 6.4): ellipsoids the filter keeps in the local maps (enough points, not longer "
                   "than k times the sensor model's expectation).",
        "%zu (%.0f%%)", m.sigma_e, 100.0 * m.sigma_e / std::max<std::size_t>(1, stored));
    row("merged", "After mean-shift merging within each merge group (docs/method.md 6.2), before occlusion removal.", "%zu",
        m.merged);
    row("fused", "Ellipsoids fused into a copy of the same surface from another merge group (docs/method.md 7).", "%zu",
        m.merged_across_groups);
    row("Sigma_e'", "Sigma_e' (docs/method.md 6.4): ellipsoids of the global map, after merging, occlusion removal and "
                    "fusion across groups.",
        "%zu", m.sigma_e_prime);
    row("merge groups", "Groups of a centre keyframe and its neighbours with edge weight >= tau_group (docs/method.md 6.1).",
        "%zu", m.groups.size());
    row("t_g", "t_g (docs/method.md 6.4): wall time of the global map build: grouping, filtering and merging, occlusion "
               "removal, fusion across groups.",
        "%.3f s", m.t_g_s);
    const TgParts parts = tgParts(m);
    row("of which", "Grouping / filtering and merging / occlusion removal / fusion across groups (docs/method.md 7) / "
                    "other (the rest of the build), ms: they add up to t_g.",
        "%.0f / %.0f / %.0f / %.0f / %.0f ms", parts.groups_ms, parts.merge_ms, parts.occlusion_ms, parts.fusion_ms,
        parts.other_ms);
    row("built from", "The frames mapped when this map was built (it is rebuilt now and then while playing).",
        "%d frames%s", win.global->frames_mapped, bench.player().status().busy ? ", rebuilding" : "");
    ImGui::EndTable();
  }
  if (stored > 0 && m.sigma_e * 20 < stored) {
    ImGui::PushStyleColor(ImGuiCol_Text, kKindColor[2]);
    ImGui::TextWrapped("The filter keeps only %.1f%% of the local maps' ellipsoids: raise the filter sigma factor k or "
                       "lower min points to keep more.",
                       100.0 * m.sigma_e / stored);
    ImGui::PopStyleColor();
  }
}

}  // namespace

void drawThresholds(Workbench& bench, WindowState& win) {
  const bool file = bench.staticMap() != nullptr;  // opening files: a map file has nothing to rebuild
  if (beginRows("thresholds")) {
    for (const Parameter& p : parameterTable())
      if (p.live) parameterRow(bench, win, p, file ? kStaticMapWhy : whyDisabled(p, bench.ui().params));
    ImGui::EndTable();
  }
  if (file) return drawStaticMapFigures(bench, win);
  if (!win.global) return ImGui::TextWrapped("No global map yet: play or step the sequence.");
  drawMapFigures(bench, win);
}

void drawRerun(Workbench& bench, WindowState& win) {
  const bool saved = bench.savedSession();
  const std::string why = bench.staticMap() ? std::string("A map file: ") + kStaticMapWhy + "."
                          : "A saved session keeps the parameters it was mapped with: there is no sequence to re-map.";
  if (beginRows("rerun")) {
    for (const Parameter& p : parameterTable())
      if (!p.live) parameterRow(bench, win, p, saved ? why : "");
    ImGui::EndTable();
  }
  bool any_pending = false;
  for (const Parameter& p : parameterTable()) any_pending |= !p.live && bench.parameters().pending(p);
  ImGui::BeginDisabled(saved || !any_pending);
  if (ImGui::Button("Re-run")) bench.parameters().rerun();
  tip(saved ? why
            : any_pending ? "Re-maps the sequence from the first frame with the values marked * (up to the frame reached)."
                          : "Nothing to apply: the sliders show the parameters the map was made with.");
  ImGui::SameLine();
  if (ImGui::Button("Revert")) bench.ui().params.mapper = win.mapping->mapper;
  tip("Puts the sliders back to the parameters the map was made with.");
  ImGui::EndDisabled();
  if (any_pending) {
    ImGui::SameLine();
    ImGui::TextColored(kPendingColor, "* pending");
  }
}

// The Screenshot row: the window or the 3-D view alone, to the name typed or a timestamped one
// in ~/Pictures/vdmap; a typed name that exists asks before it is replaced.
// A modal "FILE exists. Replace it?" while `file` is set: true when Replace is clicked; either
// button clears `file`.
static bool askToReplace(const char* title, std::string& file) {
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

static void drawScreenshot(WindowState& win) {
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

void drawView(Workbench& bench, WindowState& win) {
  Settings& s = bench.ui().settings;
  if (beginRows("view")) {
    label(win.check, "colour",
          "rgb: the surface colour; keyframe: the keyframe each ellipsoid came from (the key in the view); "
          "uncertainty: the largest standard deviation; count: points merged into it; height: height above the "
          "floor along the up axis, over the slice when it is on (colour bars in the view).");
    int color = static_cast<int>(s.color);
    if (ImGui::Combo("##colour", &color, render::kColorModeNames.data(), static_cast<int>(render::kColorModeNames.size())))
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
          "cameras (their mean image-up direction) refined by the floor's normals.");
    int up = static_cast<int>(s.up_axis);
    if (ImGui::Combo("##up", &up, kUpAxisNames, 4)) {
      s.up_axis = static_cast<UpAxis>(up);
      bench.view().resetView();
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
  if (ImGui::Button("Save view (S)")) bench.viewFiles().saveSafely(ui.view_file_text);
  tip(ui.view_file_text.empty() ? "Type a file name on the right first."
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
  std::string command = renderCommand(bench.view().spec(), bench.viewFiles().source());
  if (ImGui::Button("Copy")) ImGui::SetClipboardText(command.c_str());
  tip("Copies the `vdmap render` command that draws this view (every option spelled out) to the clipboard.");
  checkFits(win.check);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-FLT_MIN);
  ImGui::InputText("##command", &command, ImGuiInputTextFlags_ReadOnly);
  tip(command);
}

}  // namespace vdmap::app::gui
