#include "app/window/scene_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "app/window/widgets.h"
#include "mapping/core/message_text.h"
#include "mapping/core/timing.h"
#include "render/colormap.h"
#include "render/legend.h"
#include "render/view_draw.h"

namespace vdmap::app::gui {
namespace {

constexpr ImU32 kOverlayText = IM_COL32(230, 230, 230, 255), kOverlayDim = IM_COL32(170, 170, 170, 255);

// The preparation's progress bar, in the middle of the view.
void drawPreparation(ImDrawList* draw, const WindowState& win) {
  const float font = ImGui::GetFontSize();
  const std::size_t done = win.prepare_done, total = win.prepare_total;
  const Rect& view = win.layout.view;
  const float w = std::min(view.w * 0.6f, 30.f * font), x = view.x + (view.w - w) / 2, y = view.y + view.h / 2;
  const float share = total > 0 ? static_cast<float>(done) / static_cast<float>(total) : 0.f;
  char text[128];
  std::snprintf(text, sizeof text, "%s: %zu / %zu frames (first start only)", win.prepare_what.c_str(), done, total);
  draw->AddText({x, y - 1.6f * font}, kOverlayText, text);
  draw->AddRectFilled({x, y}, {x + w * share, y + font}, IM_COL32(90, 160, 230, 255));
  draw->AddRect({x, y}, {x + w, y + font}, kOverlayDim);
}

// Top left: what the view does (follows the map, looks through a keyframe) and a banner while the
// map before the last optimisation shows. The tracking lines' key is in the legend (render/legend.h).
void drawViewHints(ImDrawList* draw, const UiState& ui, const std::string& banner, const Rect& view, std::size_t strays,
                   const MapDiff* diff) {
  const float font = ImGui::GetFontSize(), pad = 0.6f * font;
  const char* mode = ui.view_from_keyframe >= 0 ? "view from keyframe (Esc leaves)"
                     : ui.follow_map            ? "following the map (a drag stops it, F resumes)"
                                                : "F: frame the map, R: reset, H: help";
  draw->AddText({view.x + pad, view.y + pad}, kOverlayDim, mode);
  float line_y = view.y + pad + 1.3f * font;
  if (ui.view_from_keyframe >= 0) {
    char text[64];
    std::snprintf(text, sizeof text, "K%d, its own intrinsics", ui.view_from_keyframe);
    draw->AddText({view.x + pad, line_y}, kOverlayDim, text);
    line_y += 1.3f * font;
  }
  if (strays > 0 && ui.view_from_keyframe < 0) {
    // Framing leaves ellipsoids far beyond the map's robust box out (render::drawnBounds).
    char text[96];
    std::snprintf(text, sizeof text, "%zu ellipsoid%s outside the frame", strays, strays == 1 ? "" : "s");
    draw->AddText({view.x + pad, line_y}, kOverlayDim, text);
    line_y += 1.3f * font;
  }
  if (diff) {  // the last edit's diff (D)
    const std::string text = diff->text() + " (removed red, new green, kept grey; D hides)";
    draw->AddText(ImGui::GetFont(), ImGui::GetFontSize(), {view.x + pad, line_y}, kOverlayText, text.c_str(), nullptr,
                  view.w - 2 * pad);
    line_y += 1.3f * font;
  }
  if (!banner.empty())  // names the optimisation B undoes (PoseEditor::beforeOptimisationBanner)
    draw->AddText(ImGui::GetFont(), font, {view.x + pad, line_y}, rgbColor(render::kLoopEdgeColor), banner.c_str(),
                  nullptr, view.w - 2 * pad);  // wrapped in a narrow view
}

// The up label's text.
std::string upAxisText(const UiState& ui) {
  const glm::vec3 up = ui.camera.up;
  char text[96];
  std::snprintf(text, sizeof text, "up: %s (%.2f, %.2f, %.2f)",
                ui.settings.up_vector ? "custom" : kUpAxisNames[static_cast<int>(ui.settings.up_axis)], up.x, up.y,
                up.z);
  return text;
}

// Bottom right: the up axis (top right in a view too narrow for it beside the legend,
// render::legendPlace).
void drawUpAxis(ImDrawList* draw, const UiState& ui, const Rect& view) {
  const float font = ImGui::GetFontSize(), pad = 0.6f * font;
  const std::string text = upAxisText(ui);
  const ImVec2 size = ImGui::CalcTextSize(text.c_str());
  const render::LegendPlace place = render::legendPlace(static_cast<int>(view.w), font);
  const float y = place.up_label_on_top ? view.y + pad : view.y + view.h - pad - size.y;
  draw->AddText({view.x + view.w - pad - size.x, y}, kOverlayDim, text.c_str());
}

}  // namespace

void syncMirror(Workbench& bench, render::MapMirror& mirror, WindowState& win) {
  Mirrored& mirrored = win.mirrored;
  UiState& ui = bench.ui();
  const Settings& s = ui.settings;
  // The style of the settings' view (viewSpecOf), as `vdmap render` draws it: draw mode (none
  // hides the map), colours, sigma, layers.
  // The height frame only where it shows (its data up axis costs a pass over the map per mapped frame).
  const bool heights = s.color == render::ColorMode::kHeight || s.slice.on;
  render::MirrorStyle style =
      render::mirrorStyle(viewSpecOf(s), heights ? bench.view().heightFrame() : render::HeightFrame{});
  // The last edit's diff (D) is drawn in its own colours (diffColoured), whatever the colour mode.
  const bool diff = bench.view().shownDiff() != nullptr;
  if (diff) style.color = render::ColorMode::kRgb;
  mirror.setStyle(style);
  // The legend: the same function and pixels as `vdmap render` (render/legend.h).
  render::GraphScene keys;
  if (bench.isOpen()) {
    const auto& mapping = *win.mapping;
    keys.tracked = mapping.mapper.poses == PoseSource::kTrack && ui.view_from_keyframe < 0;
    if (mapping.hasGroundTruth()) keys.groundtruth.resize(1);
    keys.loops.resize(mapping.loops.size());
    keys.keyframes.resize(mapping.keyframes.size());
  }
  render::Legend legend;
  if (s.show_legend) {
    legend = render::legendFor(style.color, mirror.mapColorRange(), keys, s.show_trajectory, s.show_groundtruth,
                               s.show_graph);
    if (ui.settings.query_slice) render::addQuerySliceKey(legend, ui.settings.query_slice_spec);
  }
  mirror.setLegend(  // left of the up label at the bottom-right (framebuffer pixels)
      legend, s.background,
      render::legendPlace(ui.view_width, ImGui::GetFontSize() * ImGui::GetIO().DisplayFramebufferScale.x).max_width);
  if (!bench.isOpen()) return;
  if (bench.sessionSerial() != mirrored.session) {  // generations restart with every session
    mirrored.session = bench.sessionSerial();
    mirrored.session_base += 1 << 20;
  }
  if (win.global && (s.slice.on || diff)) {
    // The slice's selection or the diff (ViewController::shownMap): negative generations, distinct
    // from every session's, so a new selection re-uploads (and re-orders the fast pass, re-keys
    // the cache).
    const ViewController::ShownMap shown = bench.view().shownMap();
    mirror.setMap(-2 - shown.serial, *shown.ellipsoids);
  } else if (win.global)
    mirror.setMap(mirrored.session_base + win.global->generation, win.global->map.ellipsoids, win.global->lod_order);
  else mirror.setMap(mirrored.session_base, {});
  const auto mapping = win.mapping;
  mirror.setFrame(mirrored.session_base + mapping->generation, mapping->rgb, mapping->depth,
                  mapping->camera.depth_scale);
  const auto scene = [&] { return bench.view().graphScene(*mapping); };
  mirror.setGraph(mirrored.session_base + mapping->generation, ui.selected_keyframe, scene,
                  ui.show_before_optimisation);
  mirror.setHighlight(ui.picked);
  mirror.setQuerySlice(bench.queries().slice());  // point queries: the slice computed for this map (or none)
  if (s.show_mesh && win.global) mirror.setSurfaceMesh(win.global->mesh);  // the mesh layer, built with the map
  const auto selection = bench.selection();
  if (selection && selection->keyframe < static_cast<int>(mapping->keyframes.size())) {
    const int id = selection->keyframe;
    const render::ContainerStyle style{
        .sigma = kContainerSigma, .color = s.color, .cell_size_px = mapping->mapper.local_map.cell_size_px};
    if (id >= 0) {
      const KeyframeInfo& k = mapping->keyframes[static_cast<std::size_t>(id)];
      // Keyed by the selection and the keyframe's pose (a pose edit re-projects nothing in the
      // container, which lives in the keyframe frame, but the ellipsoids are in the world).
      // The keyframe image is held compressed: decode it once per selection, not per UI frame.
      const int generation = mirrored.session_base + selection->serial;
      if (mirrored.decoded_rgb_for != generation) {
        mirrored.decoded_rgb = k.rgb.decode();
        mirrored.decoded_rgb_for = generation;
      }
      mirror.setContainer(generation, id, mirrored.decoded_rgb, mapping->camera, selection->T_W_K, selection->local,
                          style);
    } else {
      mirror.setContainer(mirrored.session_base + selection->serial, -1, {}, mapping->camera, Transform::Identity(), {},
                          style);
    }
  }
}

void drawScene(Workbench& bench, const render::Gl& gl, const render::MapMirror& mirror, const WindowState& win,
               render::ViewCache* cache) {
  const Rect& view = win.layout.view;
  UiState& ui = bench.ui();
  const glm::vec3 background = ui.settings.background;
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.Disable(GL_SCISSOR_TEST);
  gl.Viewport(0, 0, win.layout.fb_width, win.layout.fb_height);
  gl.ClearColor(background.r, background.g, background.b, 1.f);
  gl.ClearDepth(1.0);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (!bench.isOpen() || win.layout.fb_width <= 0 || win.layout.fb_height <= 0) return;
  const ImVec2 scale = ImGui::GetIO().DisplayFramebufferScale;
  const int vx = static_cast<int>(view.x * scale.x), vw = ui.view_width, vh = ui.view_height;
  const int vy = win.layout.fb_height - static_cast<int>(view.y * scale.y) - vh;  // GL counts rows from the bottom
  const ViewportView v = bench.view().viewport(vw, vh);
  // The scene as `vdmap render` draws it (render/view_draw.h), through the view image cache.
  if (cache)
    cache->draw(mirror, {v.camera, v.image}, background, {vx, vy, vw, vh}, ui.view_from_keyframe < 0,
                ui.settings.show_legend);
  else
    render::drawMapView(gl, mirror, {v.camera, v.image}, background, {vx, vy, vw, vh}, ui.view_from_keyframe < 0,
                        ui.settings.show_legend);
  gl.Viewport(0, 0, win.layout.fb_width, win.layout.fb_height);
}

void handleMouse(Workbench& bench, WindowState& win) {
  const Rect& view = win.layout.view;
  UiState& ui = bench.ui();
  const ImGuiIO& io = ImGui::GetIO();
  if (!bench.isOpen()) return;
  const bool over_view = view.contains(io.MousePos) && !io.WantCaptureMouse;
  for (int b = 0; b < 3; ++b)
    if (ImGui::IsMouseClicked(b)) win.drag_in_view[b] = over_view;
  const ImVec2 scale = io.DisplayFramebufferScale;
  if (win.drag_in_view[0] && ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
    if (io.KeyShift) bench.view().pan(io.MouseDelta.x * scale.x, io.MouseDelta.y * scale.y);
    else if (io.MouseDelta.x != 0 || io.MouseDelta.y != 0)
      bench.view().orbit(-io.MouseDelta.x * 0.006f, io.MouseDelta.y * 0.006f);
  }
  for (int b : {1, 2})
    if (win.drag_in_view[b] && ImGui::IsMouseDragging(b) && (io.MouseDelta.x != 0 || io.MouseDelta.y != 0))
      bench.view().pan(io.MouseDelta.x * scale.x, io.MouseDelta.y * scale.y);
  // The wheel zooms toward the point under the cursor: measure_overlay.cpp (handleViewTools).
  if (win.drag_in_view[0] && ImGui::IsMouseReleased(ImGuiMouseButton_Left)) {
    const ImVec2 drag = ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0.f);
    if (drag.x * drag.x + drag.y * drag.y < 9.f && over_view && !io.KeyCtrl)  // Ctrl+click measures
      bench.view().pick((io.MousePos.x - view.x) * scale.x, (io.MousePos.y - view.y) * scale.y, ui.view_width,
                        ui.view_height);
  }
}

void drawStatusBar(Workbench& bench, const WindowState& win) {
  const Rect& status = win.layout.status;
  UiState& ui = bench.ui();
  ImGui::SetNextWindowPos({status.x, status.y}, ImGuiCond_Always);
  ImGui::SetNextWindowSize({status.w, status.h}, ImGuiCond_Always);
  ImGui::Begin("##status", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                   ImGuiWindowFlags_NoBringToFrontOnFocus);
  char right[160];
  const std::size_t shown = win.global ? win.global->map.ellipsoids.size() : 0;
  std::snprintf(right, sizeof right, "%s | frame %.0f ms | H: help",
                counted(static_cast<long long>(shown), "ellipsoid").c_str(),
                median({win.frame_times.begin(), win.frame_times.end()}));
  // The probe (Q) leads the right side: what the map says under the cursor.
  const std::string right_text = ui.settings.probe && ui.probe_result ? ui.probe_result->text() + " | " + right : right;
  const float right_w = ImGui::CalcTextSize(right_text.c_str()).x;
  const StatusLine& st = ui.status;
  ImGui::AlignTextToFramePadding();
  if (!st.text.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, kKindColor[static_cast<int>(st.kind)]);
    const float avail = ImGui::GetContentRegionAvail().x - right_w - 3 * ImGui::GetFontSize();
    ImGui::PushClipRect(ImGui::GetCursorScreenPos(), {ImGui::GetCursorScreenPos().x + avail, status.y + status.h},
                        true);
    ImGui::TextUnformatted(st.text.c_str());
    ImGui::PopClipRect();
    ImGui::PopStyleColor();
    tip(st.text);  // the whole message, wrapped, when it is longer than the bar
    ImGui::SameLine(std::max(0.f, avail) + ImGui::GetStyle().WindowPadding.x);
    if (ImGui::SmallButton("x")) ui.status = {StatusLine::Kind::kInfo, "", st.serial + 1};
    tip("Clear the message.");
  }
  ImGui::SameLine(status.w - right_w - ImGui::GetStyle().WindowPadding.x);
  ImGui::TextUnformatted(right_text.c_str());
  tip("The probe's answer while it is on (Q); ellipsoids in the global map shown; the median time of the last 30 UI frames (the window draws only when "
      "something changes, so an idle window costs nothing).");
  ImGui::End();
}

// Legends and hints over the 3-D view (drawn in front of it, behind the panels).
void drawViewOverlay(Workbench& bench, const WindowState& win) {
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  if (win.preparing) return drawPreparation(draw, win);
  const Rect& view = win.layout.view;
  if (!bench.isOpen()) {
    const float pad = 0.6f * ImGui::GetFontSize();
    draw->AddText({view.x + pad, view.y + pad}, kOverlayDim,
                  "Open a TUM RGB-D folder or a .vdmap session (left panel).");
    return;
  }
  const UiState& ui = bench.ui();
  drawViewHints(draw, ui, bench.poses().beforeOptimisationBanner(*win.mapping), view, bench.view().framedStrays(),
                bench.view().shownDiff());
  drawUpAxis(draw, ui, view);
}

void drawHelp(Workbench& bench, WindowState& win) {
  const Rect& view = win.layout.view;
  UiState& ui = bench.ui();
  win.layout.help = {};
  if (!ui.show_help) return;
  // Over the 3-D view, as wide as it (wrapping the descriptions) but at least 40 characters.
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const float font = ImGui::GetFontSize();
  const float width = std::min(display.x * 0.95f, std::max(view.w - 2.f * font, 40.f * font));
  ImGui::SetNextWindowPos({view.x + view.w / 2, view.y + view.h / 2}, ImGuiCond_Always, {0.5f, 0.5f});
  ImGui::SetNextWindowSize({width, 0.f}, ImGuiCond_Always);  // 0: the height fits the content
  // ... up to the view's height (it scrolls beyond: more keys than a small window's view holds).
  ImGui::SetNextWindowSizeConstraints({width, 0.f}, {width, std::max(view.h - font, 10.f * font)});
  ImGui::Begin("Keys and mouse (H, F1 or Esc closes)", &ui.show_help,
               ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoResize);
  if (ImGui::BeginTable("keys", 2, ImGuiTableFlags_RowBg)) {
    ImGui::TableSetupColumn("keys", ImGuiTableColumnFlags_WidthFixed);
    ImGui::TableSetupColumn("what", ImGuiTableColumnFlags_WidthStretch);
    for (const auto& [keys, what] : keyHelp()) {
      ImGui::TableNextRow();
      ImGui::TableSetColumnIndex(0);
      ImGui::TextColored({1.f, 0.86f, 0.4f, 1.f}, "%s", keys);
      ImGui::TableSetColumnIndex(1);
      ImGui::TextWrapped("%s", what);
    }
    ImGui::EndTable();
  }
  ImGui::TextDisabled("Hover over any control or figure for what it means.");
  win.layout.help = {ImGui::GetWindowPos().x, ImGui::GetWindowPos().y, ImGui::GetWindowWidth(),
                     ImGui::GetWindowHeight()};
  ImGui::End();
}

}  // namespace vdmap::app::gui
