#include "app/window/container_window.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/window/widgets.h"

namespace vdmap::app::gui {

void drawContainerWindow(Workbench& bench, const render::MapMirror& mirror, WindowState& win) {
  float& zoom = win.container_zoom;
  ImVec2& center = win.container_center;
  UiState& ui = bench.ui();
  if (!ui.show_container || mirror.containerImage().empty() || !win.mapping) return;
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowSize({display.x * 0.55f, display.y * 0.6f}, ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowPos({display.x * 0.22f, display.y * 0.15f}, ImGuiCond_FirstUseEver);
  char title[64];
  std::snprintf(title, sizeof title, "Container view K%d###container", ui.selected_keyframe);
  if (!ImGui::Begin(title, &ui.show_container)) return ImGui::End();
  Settings& s = ui.settings;
  ImGui::Checkbox("cell grid", &s.container_grid);
  tip("The container's cells (s px of the keyframe image), drawn once they are 4 screen pixels apart.");
  ImGui::SameLine();
  ImGui::Checkbox("image bounds", &s.container_bounds);
  tip("The keyframe's own W x H image inside the 2W x 2H container.");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(8.f * ImGui::GetFontSize());
  ImGui::SliderFloat("zoom", &zoom, 1.f, 16.f, "%.1fx", ImGuiSliderFlags_Logarithmic);
  ImGui::SameLine();
  if (ImGui::Button("fit")) zoom = 1.f, center = {0.5f, 0.5f};
  const render::Texture2D& t = mirror.containerTexture();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float aspect = static_cast<float>(t.width()) / std::max(1, t.height());
  const ImVec2 size =
      avail.x / aspect <= avail.y ? ImVec2(avail.x, avail.x / aspect) : ImVec2(avail.y * aspect, avail.y);
  const ImVec2 at = ImGui::GetCursorScreenPos();
  // The visible part of the container, in texture coordinates.
  const float half = 0.5f / zoom;
  center.x = std::clamp(center.x, half, 1.f - half);
  center.y = std::clamp(center.y, half, 1.f - half);
  const ImVec2 uv0(center.x - half, center.y - half), uv1(center.x + half, center.y + half);
  ImGui::Image(textureId(t), size, uv0, uv1);
  const bool hovered = ImGui::IsItemHovered();
  if (hovered && ImGui::GetIO().MouseWheel != 0.f) {
    // Zoom about the pixel under the cursor.
    const ImVec2 m = ImGui::GetIO().MousePos;
    const ImVec2 uv(uv0.x + (m.x - at.x) / size.x * (uv1.x - uv0.x), uv0.y + (m.y - at.y) / size.y * (uv1.y - uv0.y));
    const float old_zoom = zoom;
    zoom = std::clamp(zoom * std::pow(1.25f, ImGui::GetIO().MouseWheel), 1.f, 16.f);
    const float k = old_zoom / zoom;
    center = {uv.x + (center.x - uv.x) * k, uv.y + (center.y - uv.y) * k};
  }
  if (hovered && ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
    const ImVec2 d = ImGui::GetIO().MouseDelta;
    center.x -= d.x / size.x / zoom;
    center.y -= d.y / size.y / zoom;
  }
  // Overlays in container pixels -> screen.
  const float cw = static_cast<float>(t.width()), ch = static_cast<float>(t.height());
  const auto screen = [&](float u, float v) {
    return ImVec2(at.x + (u / cw - uv0.x) / (uv1.x - uv0.x) * size.x,
                  at.y + (v / ch - uv0.y) / (uv1.y - uv0.y) * size.y);
  };
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->PushClipRect(at, {at.x + size.x, at.y + size.y}, true);
  const int cell = win.mapping->mapper.local_map.cell_size_px;
  const float px = size.x / (cw * (uv1.x - uv0.x));  // screen pixels per container pixel
  if (s.container_grid && cell * px >= 4.f) {
    const int c0 = static_cast<int>(uv0.x * cw / cell), c1 = static_cast<int>(uv1.x * cw / cell) + 1;
    const int r0 = static_cast<int>(uv0.y * ch / cell), r1 = static_cast<int>(uv1.y * ch / cell) + 1;
    for (int c = c0; c <= c1; ++c)
      draw->AddLine(screen(c * cell, 0), screen(c * cell, ch), IM_COL32(255, 255, 255, 50));
    for (int r = r0; r <= r1; ++r)
      draw->AddLine(screen(0, r * cell), screen(cw, r * cell), IM_COL32(255, 255, 255, 50));
  }
  if (s.container_bounds)
    draw->AddRect(screen(cw / 4, ch / 4), screen(cw * 3 / 4, ch * 3 / 4), IM_COL32(255, 220, 0, 200), 0.f, 0, 1.5f);
  draw->PopClipRect();
  ImGui::End();
}

}  // namespace vdmap::app::gui
