#include "app/window/measure_overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include <imgui.h>

#include "app/window/widgets.h"
#include "render/framebuffer.h"
#include "render/view_camera.h"

namespace vdmap::app::gui {
namespace {

constexpr ImU32 kMarkColor = IM_COL32(255, 60, 255, 255);     // the pick: magenta, as the highlighted ellipsoid
constexpr ImU32 kMeasureColor = IM_COL32(255, 230, 80, 255);  // the measured line
constexpr ImU32 kShadow = IM_COL32(0, 0, 0, 200);

// Where a world point shows in ImGui coordinates (nullopt behind the camera).
std::optional<ImVec2> toScreen(Workbench& bench, const WindowState& win, const glm::vec3& p) {
  const UiState& ui = bench.ui();
  const ViewportView v = bench.view().viewport(ui.view_width, ui.view_height);
  const glm::vec4 q = v.camera.T_C_W * glm::vec4(p, 1.f);
  if (q.z <= v.camera.near_m) return std::nullopt;
  const ImVec2 scale = ImGui::GetIO().DisplayFramebufferScale;
  const float u = v.camera.fx * q.x / q.z + v.camera.cx + static_cast<float>(v.image.x);
  const float w = v.camera.fy * q.y / q.z + v.camera.cy + static_cast<float>(v.image.y);
  return ImVec2(win.layout.view.x + u / scale.x, win.layout.view.y + w / scale.y);
}

// The probe's class: occupied red, free green, unknown grey (the query slice's colours).
ImU32 probeColor(const ProbeResult& r) {
  switch (r.state.state) {
    case Occupancy::kOccupied: return IM_COL32(255, 110, 100, 255);
    case Occupancy::kFree: return IM_COL32(110, 230, 130, 255);
    case Occupancy::kUnknown: break;
  }
  return IM_COL32(200, 200, 200, 255);
}

void label(ImDrawList* draw, ImVec2 at, ImU32 color, const char* text) {
  const ImVec2 size = ImGui::CalcTextSize(text);
  draw->AddRectFilled({at.x - 3, at.y - 2}, {at.x + size.x + 3, at.y + size.y + 2}, kShadow, 3.f);
  draw->AddText(at, color, text);
}

// The view pixel under the mouse (framebuffer pixels, top-left origin of the viewport).
ImVec2 mouseInView(const WindowState& win) {
  const ImGuiIO& io = ImGui::GetIO();
  return {(io.MousePos.x - win.layout.view.x) * io.DisplayFramebufferScale.x,
          (io.MousePos.y - win.layout.view.y) * io.DisplayFramebufferScale.y};
}

}  // namespace

std::string distanceText(const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 d = b - a;
  char text[128];
  std::snprintf(text, sizeof text, "%.3f m (%+.3f %+.3f %+.3f)", glm::length(d), d.x, d.y, d.z);
  return text;
}

void handleViewTools(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  const ImGuiIO& io = ImGui::GetIO();
  const bool over_view = win.layout.view.contains(io.MousePos) && !io.WantCaptureMouse;
  const ImVec2 at = mouseInView(win);
  // P (Workbench::key) or a double-click: turn about the point under the cursor.
  const bool pivot = std::exchange(ui.pivot_requested, false);
  if (!bench.isOpen() || !over_view) return;
  // The probe (Q) follows the cursor: asked every frame over the view (a frame is drawn only
  // after input or news, such as the queries of a new map).
  if (ui.settings.probe) win.probes.push_back({ViewProbe::Purpose::kQuery, at.x, at.y});
  if (pivot || win.double_click) win.probes.push_back({ViewProbe::Purpose::kPivot, at.x, at.y});
  if (io.MouseWheel != 0.f && ui.settings.probe && io.KeyAlt)  // the probe's offset, 25 % a step
    ui.settings.probe_offset_m = std::clamp(ui.settings.probe_offset_m * std::pow(1.25f, io.MouseWheel), 0.005f, 1.f);
  else if (io.MouseWheel != 0.f) win.probes.push_back({ViewProbe::Purpose::kZoom, at.x, at.y, io.MouseWheel});
  if (io.KeyCtrl && ImGui::IsMouseReleased(ImGuiMouseButton_Left) && win.drag_in_view[0]) {
    const ImVec2 drag = ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0.f);
    if (drag.x * drag.x + drag.y * drag.y < 9.f) win.probes.push_back({ViewProbe::Purpose::kMeasure, at.x, at.y});
  }
}

std::optional<glm::vec3> probeView(Workbench& bench, const render::Gl& gl, const WindowState& win, float x_px,
                                   float y_px) {
  const UiState& ui = bench.ui();
  const int vw = ui.view_width, vh = ui.view_height;
  const int px = static_cast<int>(std::floor(x_px)), py = static_cast<int>(std::floor(y_px));
  if (px < 0 || py < 0 || px >= vw || py >= vh) return std::nullopt;
  // Where drawScene drew the view (GL counts rows from the bottom).
  const ImVec2 scale = ImGui::GetIO().DisplayFramebufferScale;
  const int vx = static_cast<int>(win.layout.view.x * scale.x);
  const int vy = win.layout.fb_height - static_cast<int>(win.layout.view.y * scale.y) - vh;
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.ReadBuffer(GL_BACK);
  const std::optional<float> depth = render::readDepth(gl, vx + px, vy + (vh - 1 - py));
  if (!depth) return std::nullopt;
  const ViewportView v = bench.view().viewport(vw, vh);
  return render::unproject(v.camera, static_cast<float>(px - v.image.x), static_cast<float>(py - v.image.y), *depth);
}

bool answerProbes(Workbench& bench, const render::Gl& gl, WindowState& win) {
  const UiState& ui = bench.ui();
  bool changed = false;
  for (const ViewProbe& probe : win.probes) {
    const std::optional<glm::vec3> p = probeView(bench, gl, win, probe.x_px, probe.y_px);
    switch (probe.purpose) {
      case ViewProbe::Purpose::kZoom:
        // Toward the surface under the cursor, else the point of the target's plane there.
        bench.view().zoomAt(
            probe.wheel, p ? *p : bench.view().targetPlanePoint(probe.x_px, probe.y_px, ui.view_width, ui.view_height));
        break;
      case ViewProbe::Purpose::kPivot:
        if (p) bench.view().pivotAt(*p);
        else bench.report(StatusLine::Kind::kInfo, "no surface under the cursor to turn about");
        break;
      case ViewProbe::Purpose::kMeasure:
        if (p) bench.view().addMeasurePoint(*p);
        else bench.report(StatusLine::Kind::kInfo, "no surface under the cursor to measure at");
        break;
      case ViewProbe::Purpose::kQuery:
        changed = bench.queries().probeAt(probe.x_px, probe.y_px, ui.view_width, ui.view_height, p) || changed;
        break;
    }
  }
  win.probes.clear();
  return changed;
}

void drawViewMarks(Workbench& bench, const WindowState& win) {
  if (!bench.isOpen() || win.preparing) return;
  const UiState& ui = bench.ui();
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  const Rect& view = win.layout.view;
  draw->PushClipRect({view.x, view.y}, {view.x + view.w, view.y + view.h});
  if (ui.picked) {
    // A ring and a cross about 12 px wide at the projected centre, clamped to the view's edge
    // when it lies outside (the 3-D diamond alone is a few pixels at room distance).
    const glm::vec3 mean(ui.picked->mean.x(), ui.picked->mean.y(), ui.picked->mean.z());
    if (const auto at = toScreen(bench, win, mean)) {
      const float r = 12.f, pad = r + 2.f;
      const ImVec2 c(std::clamp(at->x, view.x + pad, view.x + view.w - pad),
                     std::clamp(at->y, view.y + pad, view.y + view.h - pad));
      for (const auto& [color, width] : {std::pair{kShadow, 4.f}, std::pair{kMarkColor, 2.f}}) {
        draw->AddCircle(c, r, color, 24, width);
        draw->AddLine({c.x - 1.6f * r, c.y}, {c.x - 0.5f * r, c.y}, color, width);
        draw->AddLine({c.x + 0.5f * r, c.y}, {c.x + 1.6f * r, c.y}, color, width);
        draw->AddLine({c.x, c.y - 1.6f * r}, {c.x, c.y - 0.5f * r}, color, width);
        draw->AddLine({c.x, c.y + 0.5f * r}, {c.x, c.y + 1.6f * r}, color, width);
      }
    }
  }
  const auto dot = [&](const glm::vec3& p, const char* name) -> std::optional<ImVec2> {
    const auto at = toScreen(bench, win, p);
    if (!at) return at;
    draw->AddCircleFilled(*at, 5.f, kShadow);
    draw->AddCircleFilled(*at, 3.5f, kMeasureColor);
    label(draw, {at->x + 7.f, at->y - 7.f - ImGui::GetFontSize()}, kMeasureColor, name);
    return at;
  };
  if (ui.settings.probe && ui.probe_result) {
    // The probe: a dot at its point (under the cursor: the point lies on the cursor's ray), the
    // answer beside it, or left of it where the view ends.
    const ProbeResult& r = *ui.probe_result;
    if (const auto at = toScreen(bench, win, r.point)) {
      draw->AddCircleFilled(*at, 4.f, kShadow);
      draw->AddCircleFilled(*at, 2.5f, probeColor(r));
      const std::string text = r.text();
      const ImVec2 size = ImGui::CalcTextSize(text.c_str());
      float x = at->x + 16.f + size.x > view.x + view.w ? at->x - 10.f - size.x : at->x + 16.f;
      x = std::max(view.x + 4.f, std::min(x, view.x + view.w - size.x - 4.f));  // wider than the room beside it
      label(draw, {x, at->y + 12.f}, probeColor(r), text.c_str());
    }
  }
  if (ui.measure_a) {
    const auto a = dot(*ui.measure_a, "A");
    const auto b = ui.measure_b ? dot(*ui.measure_b, "B") : std::nullopt;
    if (a && b) {
      draw->AddLine(*a, *b, kShadow, 4.f);
      draw->AddLine(*a, *b, kMeasureColor, 2.f);
      const std::string text = distanceText(*ui.measure_a, *ui.measure_b);
      label(draw, {0.5f * (a->x + b->x) + 6.f, 0.5f * (a->y + b->y) + 4.f}, kMeasureColor, text.c_str());
    }
  }
  draw->PopClipRect();
}

}  // namespace vdmap::app::gui
