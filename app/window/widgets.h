#pragma once
// Small Dear ImGui helpers the workbench's panels share: tooltips, labelled rows, collapsible
// sections, colour swatches and ramps, and the check that every label fits (the scripted run's
// layout figures count the ones that do not).
#include <string>

#include <imgui.h>

#include "render/scene_types.h"
#include "render/texture.h"

namespace vdmap::app::gui {

/// The text colour of a parameter edited but not yet in the map shown.
inline const ImVec4 kPendingColor(1.f, 0.7f, 0.25f, 1.f);
/// The status line's text colours by StatusLine::Kind (info, success, warning, error).
inline const ImVec4 kKindColor[] = {
    {0.85f, 0.85f, 0.85f, 1}, {0.45f, 0.9f, 0.45f, 1}, {1.f, 0.8f, 0.3f, 1}, {1.f, 0.42f, 0.42f, 1}};

/// A rectangle in ImGui coordinates (top-left origin, pixels of the display).
struct Rect {
  float x = 0, y = 0, w = 0, h = 0;
  bool contains(ImVec2 p) const { return p.x >= x && p.y >= y && p.x < x + w && p.y < y + h; }
};

/// What the widgets below obey and count during one UI frame.
struct LayoutCheck {
  bool expand_sections = false;  ///< every collapsible section open (the script's --expand-sections)
  int labels_cut = 0;            ///< labels and buttons this frame that did not fit their window or table cell
};

/// A GL texture as Dear ImGui's OpenGL 3 backend takes it.
ImTextureID textureId(const render::Texture2D& t);
ImU32 rgbColor(const glm::u8vec3& c);
/// A tooltip for the last item, shown also when it is disabled (then it says why); none for "".
void tip(const std::string& text);
/// A horizontal colour ramp (viridis) from `at` of size w x h into `draw`.
void drawRamp(ImDrawList* draw, ImVec2 at, float w, float h);
/// Text wrapped to the space left on the line, breaking after spaces and '/' (a path breaks
/// between folders, not inside a name; breakLines).
void textWrapped(const std::string& text);
/// A length as the panels print it: mm below a metre, else m.
std::string metres(double m);

/// Opens a docked panel at r; r becomes where it is, `width` its width (the user may drag its
/// inner edge, up to 45 % of `display_width`). Close it with ImGui::End().
void beginPanel(const char* name, Rect& r, float& width, float display_width);
/// Starts a two-column table of labelled rows (label, then widget); false: nothing to draw (no
/// EndTable then).
bool beginRows(const char* id);
/// How many beginRows tables drawn since the last call were still sizing their columns (their
/// labels clipped until a later frame); resets the count.
int takeTablesSettling();
/// A row of a beginRows table: the label (never cut: its column fits the widest) and a
/// tooltip, then the widget fills the rest of the row. Pending: in kPendingColor.
void label(LayoutCheck& check, const char* text, const std::string& help, bool pending = false);
/// Counts the last item when it does not fit in its window or table cell (the scripted stats
/// report the count: every label and button must be readable at every window size).
void checkFits(LayoutCheck& check);
/// A collapsible section of a panel (all open when check.expand_sections); true when open.
bool section(const LayoutCheck& check, const char* name, bool open_by_default = false);
/// A colour swatch as wide as a short line, in the text's row (the next item follows on it).
void swatch(const glm::u8vec3& color);

}  // namespace vdmap::app::gui
