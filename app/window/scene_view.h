#pragma once
// The 3-D view between the panels: the GPU mirror kept in step with the snapshots, the scene
// drawn under the panels, the mouse (orbit, pan, zoom, pick), the legends over it, the status
// line below and the help overlay.
#include "app/window/window_state.h"
#include "render/view_cache.h"

namespace vdmap::app::gui {

/// Sends what changed in this frame's snapshots (win.mapping, win.global, the selection) and the
/// view settings to `mirror`.
void syncMirror(Workbench& bench, render::MapMirror& mirror, WindowState& win);
/// Clears the window and draws the map into the 3-D viewport (letterboxed when viewing from a
/// keyframe); call after ImGui::Render, before the panels are drawn over it. With a view image
/// cache, a view whose picture has not changed is copied from it rather than drawn again.
void drawScene(Workbench& bench, const render::Gl& gl, const render::MapMirror& mirror, const WindowState& win,
               render::ViewCache* cache = nullptr);
/// Drags, wheel and clicks over the 3-D view (none that ImGui's windows take).
void handleMouse(Workbench& bench, WindowState& win);
/// The status line: the last message, the map's size and the UI frame time.
void drawStatusBar(Workbench& bench, const WindowState& win);
/// Legends and hints over the 3-D view (in front of it, behind the panels); the preparation's
/// progress while it runs.
void drawViewOverlay(Workbench& bench, const WindowState& win);
/// The keys and mouse overlay (H); win.layout.help is where it is (all zero when closed).
void drawHelp(Workbench& bench, WindowState& win);

}  // namespace vdmap::app::gui
