#pragma once
// What the workbench window keeps from one UI frame to the next besides the model (the
// Workbench's worker), the UI state (UiState) and the GPU resources (render::MapMirror): the
// snapshots a frame draws, where the panels are, what the mirror was given, and the panels' own
// drag state. The panel, view and script functions take it by reference (immediate mode: the
// frame is drawn again from it and the model every time, no widget objects).
#include <array>
#include <cstddef>
#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <imgui.h>

#include "app/window/file_browser.h"
#include "app/window/widgets.h"
#include "app/workbench/workbench.h"
#include "render/map_mirror.h"

namespace vdmap::app::gui {

/// Where the panels, the status bar, the 3-D view and the help overlay are (ImGui coordinates),
/// and the panel widths (the defaults, or where the user dragged them).
struct Layout {
  Rect left, right, status, view, help;  ///< help: all zero while it is closed
  float left_w = 0, right_w = 0, status_h = 0;
  ImVec2 last_size{0, 0};           ///< the display size the widths were fitted to
  int fb_width = 0, fb_height = 0;  ///< the framebuffer, pixels
};

/// Keys pressed since the last UI frame, kept by GLFW's key callback so that a tap shorter than
/// one frame is never lost (Dear ImGui 1.86 only keeps which keys are down at the frame's start).
struct KeyQueue {
  std::deque<std::pair<int, int>> presses;  ///< (GLFW key, modifiers)
  int events = 0;                           ///< any input at all since the last frame
  std::vector<std::string> dropped;         ///< paths dropped on the window (FileActions::drop takes them)
  DoubleClick double_click;                 ///< told from the presses' times (a slow frame loses it otherwise)
  int double_clicks = 0;                    ///< double clicks since the last frame
};

/// What the GPU mirror was last given, to key its generations.
struct Mirrored {
  int session = 0;           ///< the Workbench::sessionSerial mirrored
  int session_base = 0;      ///< added to the snapshots' generations, which restart with every session
  int decoded_rgb_for = -1;  ///< the container generation decoded_rgb was decoded for
  cv::Mat decoded_rgb;       ///< the selected keyframe's image, decoded once per selection
};

/// A question about the point under a pixel of the 3-D view, answered once the scene is drawn
/// (measure_overlay.h answerProbes).
struct ViewProbe {
  enum class Purpose { kZoom, kPivot, kMeasure, kQuery };  // kQuery: the probe (Q) under the cursor
  Purpose purpose = Purpose::kMeasure;
  float x_px = 0, y_px = 0;  ///< viewport framebuffer pixels, top-left origin
  float wheel = 0;           ///< kZoom: wheel steps
};

/// The window's own state (see the top of this file); the UI thread alone uses it.
struct WindowState {
  /// The snapshots this frame draws, taken once after Workbench::sync (the worker may publish
  /// newer ones meanwhile; the frame stays consistent). Null while nothing is open.
  std::shared_ptr<const MappingSnapshot> mapping;
  std::shared_ptr<const GlobalSnapshot> global;
  Layout layout;
  LayoutCheck check;
  Mirrored mirrored;
  /// The preparation (rendering the built-in scene on first start) while it runs.
  bool preparing = false;
  std::string prepare_what;
  std::size_t prepare_done = 0, prepare_total = 0;  ///< frames
  bool double_click = false;  ///< the left button was double-clicked since the last frame (KeyQueue)
  // The sequence panel.
  float below_images_px = 0;  ///< its depth scale and stage times, as last drawn
  int scrub = 0;              ///< the scrubber's frame
  bool scrubbing = false;     ///< the scrubber is being dragged (it does not follow the player then)
  // The 3-D view and the container window.
  std::array<bool, 3> drag_in_view{};  ///< per mouse button: its drag started over the 3-D view
  float container_zoom = 1.f;
  ImVec2 container_center{0.5f, 0.5f};  ///< texture coordinates
  // The view section's screenshot: the file typed ("": a timestamped name in screenshotFolder()),
  // what it shows (the 3-D view alone or the window), and one asked for (taken after the frame
  // is drawn; an existing typed name asks first).
  std::string screenshot_text, screenshot_request, screenshot_confirm;
  bool screenshot_view_only = false, screenshot_request_view = false;
  std::vector<ViewProbe> probes;  ///< mouse actions waiting for the drawn scene's depth

  std::deque<double> frame_times;  ///< the last 30 UI frames' times, ms (the status line's median)
  FileBrowser browser;             ///< Browse... beside Open (opening files)
};

}  // namespace vdmap::app::gui
