#include "app/window/file_browser.h"

#include <algorithm>
#include <filesystem>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "app/cli/error_text.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {
namespace fs = std::filesystem;
namespace {

// The folder the path field names, and the start of a name typed after it ("" : none).
std::pair<fs::path, std::string> folderAndPrefix(const std::string& text) {
  std::error_code ec;
  const fs::path p = text.empty() ? fs::current_path(ec) : fs::path(text);
  if (fs::is_directory(p, ec)) return {p, ""};
  return {p.parent_path().empty() ? fs::path(".") : p.parent_path(), p.filename().string()};
}

void relist(FileBrowser& b, const fs::path& folder) {
  const std::string key = folder.string();
  if (key == b.listed) return;
  b.listed = key;
  b.selected = -1;
  b.error.clear();
  try {
    b.entries = listFolder(folder);
  } catch (const std::exception& e) {
    b.entries.clear();
    b.error = errorMessage(e);
  }
}

// Absolute, normal, and without a trailing separator (so parent_path is the folder above).
fs::path clean(const fs::path& p) {
  std::error_code ec;
  fs::path c = fs::absolute(p, ec).lexically_normal();
  if (c.filename().empty() && c != c.root_path()) c = c.parent_path();
  return c;
}

std::string withSlash(const fs::path& p) {
  std::string s = p.string();
  if (!s.empty() && s.back() != '/') s += '/';
  return s;
}

}  // namespace

void openFileBrowser(FileBrowser& b, const std::string& start) {
  std::error_code ec;
  fs::path folder = start.empty() ? fs::current_path(ec) : fs::absolute(start, ec);
  while (!folder.empty() && !fs::is_directory(folder, ec) && folder != folder.parent_path())
    folder = folder.parent_path();
  if (folder.empty()) folder = fs::current_path(ec);
  b.path = withSlash(clean(folder));
  b.listed.clear();
  b.open = true;
}

std::string drawFileBrowser(FileBrowser& b, bool double_click) {
  if (!b.open) return "";
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos({vp->WorkPos.x + vp->WorkSize.x * 0.5f, vp->WorkPos.y + vp->WorkSize.y * 0.5f},
                          ImGuiCond_Appearing, {0.5f, 0.5f});
  ImGui::SetNextWindowSize({std::min(700.f, vp->WorkSize.x * 0.8f), std::min(480.f, vp->WorkSize.y * 0.8f)},
                           ImGuiCond_Appearing);
  std::string chosen;
  if (!ImGui::Begin("Open a file", &b.open, ImGuiWindowFlags_NoCollapse)) {
    ImGui::End();
    return chosen;
  }
  const auto [folder, prefix] = folderAndPrefix(b.path);
  relist(b, folder);
  if (ImGui::Button("Up")) {
    b.path = withSlash(clean(folder).parent_path());
    b.selected = -1;
  }
  tip("The folder above this one.");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-FLT_MIN);
  const bool enter = ImGui::InputText("##path", &b.path, ImGuiInputTextFlags_EnterReturnsTrue);
  tip("A folder to list, or a folder and the start of a name to find; Enter opens what it names.");
  // Entries that match what is typed after the folder.
  std::vector<int> shown;
  for (int i = 0; i < static_cast<int>(b.entries.size()); ++i)
    if (b.entries[static_cast<std::size_t>(i)].path.filename().string().rfind(prefix, 0) == 0) shown.push_back(i);
  const float footer = ImGui::GetFrameHeightWithSpacing() + ImGui::GetStyle().ItemSpacing.y;
  if (!b.error.empty()) ImGui::TextWrapped("%s", b.error.c_str());
  if (ImGui::BeginTable("entries", 2, ImGuiTableFlags_ScrollY | ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV,
                        {0.f, -footer})) {
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("name", ImGuiTableColumnFlags_WidthStretch);
    ImGui::TableSetupColumn("opens as", ImGuiTableColumnFlags_WidthFixed, ImGui::CalcTextSize("ellipsoid PLY__").x);
    ImGui::TableHeadersRow();
    for (const int i : shown) {
      const FolderEntry& e = b.entries[static_cast<std::size_t>(i)];
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      const std::string name = e.path.filename().string() + (e.folder ? "/" : "");
      if (!e.folder && !e.kind) ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
      const bool clicked = ImGui::Selectable(
          name.c_str(), b.selected == i, ImGuiSelectableFlags_SpanAllColumns | ImGuiSelectableFlags_AllowDoubleClick);
      if (!e.folder && !e.kind) ImGui::PopStyleColor();
      const bool twice = double_click && ImGui::IsItemHovered();
      if (clicked || twice) {
        b.selected = i;
        if (twice) {
          // A plain folder is entered; a sequence or map folder, and any file vdmap opens, is opened.
          if (e.folder && !e.kind) b.path = withSlash(e.path);
          else if (e.kind) chosen = e.path.string();
        }
      }
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(e.kind ? mapFileKindName(*e.kind) : e.folder ? "folder" : "");
    }
    ImGui::EndTable();
  }
  const FolderEntry* sel = b.selected >= 0 && b.selected < static_cast<int>(b.entries.size())
                               ? &b.entries[static_cast<std::size_t>(b.selected)]
                               : nullptr;
  ImGui::BeginDisabled(!sel || !sel->kind);
  if (ImGui::Button("Open") && sel && sel->kind) chosen = sel->path.string();
  tip(sel && sel->kind ? "Opens the entry selected." : "Select something vdmap opens (a kind is shown beside it).");
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Cancel")) b.open = false;
  if (enter && prefix.empty()) {
    // Enter on a folder: open it when it is a sequence or map folder.
    try {
      detectMapFile(folder);
      chosen = folder.string();
    } catch (const std::exception&) {
    }
  } else if (enter && shown.size() == 1 && b.entries[static_cast<std::size_t>(shown[0])].kind) {
    chosen = b.entries[static_cast<std::size_t>(shown[0])].path.string();
  }
  ImGui::End();
  if (!chosen.empty()) b.open = false;
  return chosen;
}

}  // namespace vdmap::app::gui
