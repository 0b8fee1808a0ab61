#pragma once
// The workbench window: GLFW + Dear ImGui drawing of a Workbench (all logic lives there).
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "app/workbench/workbench.h"

namespace vdmap::app::gui {

/// The scripted path for tests and documentation screenshots.
struct ScriptOptions {
  bool play_to_end = false;   ///< press Play at start
  int keyframe = -1;          ///< select this keyframe in the inspector before the screenshot
  std::vector<int> press;     ///< GLFW keys pressed then, before the screenshot (keyNames())
  bool expand_sections = false;  ///< every collapsible section of the panels open (layout checks)
  std::string screenshot;     ///< PNG of the window, taken once mapping and map building are done
  std::string stats_json;     ///< figures (Sigma_e, Sigma_e', t_g, UI frame time) written then too
  /// The headless twin (docs/workbench.md "Save view"): a view shown instead of the default one
  /// once mapping is done (--view-file), the view then saved as a view file (--save-view) and
  /// the 3-D view's own image, without the panels, at the view's size (--view-screenshot).
  std::optional<render::ViewSpec> view;
  std::string save_view, view_screenshot;
  bool exit = false;          ///< close the window once the above are written
  /// Measurements, in this order after the screenshot, into the stats file:
  int latency_runs = 0;       ///< slider-to-map latency: merge-distance edits until the new map is drawn, ms
  int orbit_frames = 0;       ///< UI frame time while orbiting, ms per frame
  double idle_seconds = 0;    ///< process CPU time over this many seconds of nothing happening
  /// Close the window as a user would after this many frames drawn (0: never); a test of
  /// closing during the preparation.
  int close_after_frames = 0;
  /// Paths dropped on the window once mapping is done, with the --press keys (--drop): through
  /// the drop queue, so the next frame opens them (a view file is applied as a view).
  std::vector<std::string> drop;
  // Progressive drawing (docs/performance.md "Workbench"):
  /// Ellipsoids the fast pass draws while the camera moves; 0: adapted to the frame times.
  std::size_t fast_budget = 0;
  /// Measuring: view pixels x1, y1, x2, y2 (the 3-D viewport's framebuffer pixels, top-left
  /// origin) probed once the screenshot's frame is drawn (stats: measure {a, b, distance_m}).
  std::vector<float> measure;
  // Point queries (docs/workbench.md "Queries"):
  /// The probe at view pixel x, y (as the mouse there with Q on) once the screenshot's frame is
  /// drawn (stats: probe {class, p, distance_m, point}); empty: none.
  std::vector<float> probe;
  /// The query slice shown from the start (--query-slice, --query-slice-color); the screenshot
  /// waits for it (stats: query_slice).
  std::optional<render::QuerySliceSpec> query_slice;
};

/// Work to do before the sequence can be opened (rendering the built-in scene on first start):
/// run on its own thread while the window shows its progress. run() reports (done, total) and
/// returns the folder to open with `args`; it stops soon after cancelled() turns true (the window
/// was closed), throwing and leaving nothing half-written.
struct Preparation {
  std::string what;
  SequenceArgs args;
  std::function<std::string(const std::function<void(std::size_t, std::size_t)>& progress,
                            const std::function<bool()>& cancelled)>
      run;
};

/// The keys --press takes, by name ("space", "right", "h", ...), as GLFW key codes. Throws
/// std::invalid_argument naming the key for an unknown name.
std::vector<int> parseKeyNames(const std::string& comma_separated);

/// Opens the window (and runs `prepare` first when given), runs until it is closed (or the script
/// is done with `exit`). `settings_file`'s folder keeps the window layout (imgui.ini) unless it is
/// empty; the window size goes into bench.ui().settings. Returns the exit code. Throws
/// std::runtime_error when no window can be opened.
int runWorkbenchWindow(Workbench& bench, const ScriptOptions& script, const std::string& settings_file,
                       Preparation prepare = {});

}  // namespace vdmap::app::gui
