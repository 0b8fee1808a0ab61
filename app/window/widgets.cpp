#include "app/window/widgets.h"

#include <algorithm>
#include <cfloat>
#include <cstdint>
#include <cstdio>
#include <utility>

#include <imgui_internal.h>

#include "app/workbench/workbench_state.h"
#include "render/colormap.h"
#include "render/legend.h"

namespace vdmap::app::gui {

ImTextureID textureId(const render::Texture2D& t) {
  return reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(t.id()));
}

ImU32 rgbColor(const glm::u8vec3& c) { return IM_COL32(c.r, c.g, c.b, 255); }

void tip(const std::string& text) {
  if (text.empty() || !ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) return;
  ImGui::BeginTooltip();
  ImGui::PushTextWrapPos(ImGui::GetFontSize() * 32.f);
  ImGui::TextUnformatted(text.c_str());
  ImGui::PopTextWrapPos();
  ImGui::EndTooltip();
}

void drawRamp(ImDrawList* draw, ImVec2 at, float w, float h) {
  constexpr int kSteps = 32;
  for (int i = 0; i < kSteps; ++i) {
    const float x0 = at.x + w * i / kSteps, x1 = at.x + w * (i + 1) / kSteps;
    draw->AddRectFilled({x0, at.y}, {x1 + 0.5f, at.y + h}, rgbColor(render::colormap((i + 0.5f) / kSteps)));
  }
  draw->AddRect(at, {at.x + w, at.y + h}, IM_COL32(200, 200, 200, 160));
}

void textWrapped(const std::string& text) {
  const float width = std::max(1.f, ImGui::GetContentRegionAvail().x);
  ImGui::TextUnformatted(breakLines(text, width, [](std::string_view s) {
                           return ImGui::CalcTextSize(s.data(), s.data() + s.size()).x;
                         }).c_str());
}

std::string metres(double m) { return render::metresText(m); }

void beginPanel(const char* name, Rect& r, float& width, float display_width) {
  const float font = ImGui::GetFontSize();
  ImGui::SetNextWindowPos({r.x, r.y}, ImGuiCond_Always);
  ImGui::SetNextWindowSize({r.w, r.h}, ImGuiCond_Always);
  ImGui::SetNextWindowSizeConstraints({18.f * font, r.h}, {std::max(18.f * font, display_width * 0.45f), r.h});
  ImGui::Begin(name, nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoBringToFrontOnFocus);
  const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
  if (size.x != r.w) width = size.x;  // dragged: next frame re-docks with the new width
  r = {pos.x, pos.y, size.x, size.y};
}

namespace {
int tables_settling = 0;  // beginRows tables still sizing their columns this frame
}  // namespace

bool beginRows(const char* id) {
  if (!ImGui::BeginTable(id, 2, ImGuiTableFlags_SizingFixedFit)) return false;
  ImGui::TableSetupColumn("label", ImGuiTableColumnFlags_WidthFixed);
  ImGui::TableSetupColumn("value", ImGuiTableColumnFlags_WidthStretch);
  // A new table fits its label column to what the previous frame measured (Dear ImGui's
  // auto-fit queue), so its first frames clip the labels: they need frames after this one.
  if (const ImGuiTable* table = ImGui::GetCurrentTable()) {
    bool settling = table->IsInitializing;
    for (int c = 0; c < table->ColumnsCount; ++c) settling |= table->Columns[c].AutoFitQueue != 0;
    tables_settling += settling;
  }
  return true;
}

int takeTablesSettling() { return std::exchange(tables_settling, 0); }

void label(LayoutCheck& check, const char* text, const std::string& help, bool pending) {
  ImGui::TableNextRow();
  ImGui::TableSetColumnIndex(0);
  ImGui::AlignTextToFramePadding();
  if (pending) ImGui::PushStyleColor(ImGuiCol_Text, kPendingColor);
  ImGui::TextUnformatted(text);
  if (pending) ImGui::PopStyleColor();
  checkFits(check);
  tip(help);
  ImGui::TableSetColumnIndex(1);
  ImGui::SetNextItemWidth(-FLT_MIN);
}

void checkFits(LayoutCheck& check) {
  if (ImGui::GetItemRectMax().x > ImGui::GetWindowPos().x + ImGui::GetWindowWidth() - 1.f) ++check.labels_cut;
  else if (ImGui::GetItemRectMax().x > ImGui::GetCursorScreenPos().x + ImGui::GetContentRegionAvail().x + 1.f &&
           ImGui::GetContentRegionAvail().x > 0)
    ++check.labels_cut;
}

bool section(const LayoutCheck& check, const char* name, bool open_by_default) {
  if (check.expand_sections) ImGui::SetNextItemOpen(true, ImGuiCond_Always);
  return ImGui::CollapsingHeader(name, open_by_default ? ImGuiTreeNodeFlags_DefaultOpen : 0);
}

void swatch(const glm::u8vec3& color) {
  const float h = ImGui::GetTextLineHeight();
  const ImVec2 at = ImGui::GetCursorScreenPos();
  const float y = at.y + ImGui::GetStyle().FramePadding.y + 0.5f * h;
  ImGui::GetWindowDrawList()->AddLine({at.x, y}, {at.x + 1.4f * h, y}, rgbColor(color), 3.f);
  ImGui::Dummy({1.4f * h, ImGui::GetFrameHeight()});
  ImGui::SameLine();
}

}  // namespace vdmap::app::gui
