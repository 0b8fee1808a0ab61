#pragma once
// The scripted run (--play-to-end, --screenshot, --stats, --exit ...) without a window: once
// mapping and map building are done, reset the view, draw a few frames, take the screenshot,
// then the measurements asked for (slider-to-map latency, orbit frame time, idle CPU), then
// write the figures. The window calls advanceScript once per drawn frame and does what only it
// can (the depth under a pixel, the screenshot, the layout) through ScriptWindow.
#include <chrono>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/workbench/workbench.h"
#include "render/query_slice.h"
#include "render/view_spec.h"

namespace vdmap::app::gui {

/// The scripted path for tests and documentation screenshots.
struct ScriptOptions {
  bool play_to_end = false;  ///< press Play at start
  int keyframe = -1;         ///< select this keyframe in the inspector before the screenshot
  std::vector<int> press;    ///< keys pressed then, before the screenshot (the window's codes, parseKeyNames)
  /// Threshold edits KEY=VALUE made then, before the keys, as a slider makes them (stats: edit_diff).
  std::vector<std::string> edit;
  bool expand_sections = false;  ///< every collapsible section of the panels open (layout checks)
  std::string screenshot;        ///< PNG of the window, taken once mapping and map building are done
  std::string stats_json;        ///< figures (Sigma_e, Sigma_e', t_g, UI frame time) written then too
  /// The headless twin (docs/workbench.md "Save view"): a view shown instead of the default one
  /// once mapping is done (--view-file), the view then saved as a view file (--save-view) and
  /// the 3-D view's own image, without the panels, at the view's size (--view-screenshot).
  std::optional<render::ViewSpec> view;
  std::string save_view, view_screenshot;
  bool exit = false;  ///< close the window once the above are written
  /// Measurements, in this order after the screenshot, into the stats file:
  int latency_runs = 0;     ///< slider-to-map latency: merge-distance edits until the new map is drawn, ms
  int orbit_frames = 0;     ///< UI frame time while orbiting, ms per frame
  double idle_seconds = 0;  ///< process CPU time over this many seconds of nothing happening
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

enum class ScriptPhase { kWaitDone, kSettle, kLatency, kOrbit, kIdle, kFinish, kDone };

/// The script's options and its progress through them.
struct ScriptRun {
  using Clock = std::chrono::steady_clock;
  ScriptOptions options;
  ScriptPhase phase = ScriptPhase::kWaitDone;
  int countdown = 0;                                 ///< frames to draw before the screenshot
  bool finished = false;                             ///< done, and the window should close (options.exit)
  bool screenshot_taken = false;                     ///< by the script, so a failure removes it (and no older file)
  bool view_files_taken = false;                     ///< --save-view / --view-screenshot, likewise
  nlohmann::json layout = nlohmann::json::object();  ///< recordLayout's figures
  nlohmann::json measure;                            ///< --measure's points and distance (null: none asked or found)
  nlohmann::json probe;                              ///< --probe's answer (null: none asked)
  int latency_generation = -1;                       ///< the global map an edit waits to replace (-1: no edit pending)
  Clock::time_point latency_start, orbit_frame_start, idle_until;
  std::vector<double> latency_ms, orbit_ms, orbit_cpu_ms;
  // Latency stages (global map stream): per edit, from the GlobalSnapshot's stamps.
  std::vector<nlohmann::json> latency_stages;
  bool latency_shown_pending = false;  ///< the frame drawing the edited map is not on screen yet
  double latency_back = 0;             ///< the value the next edit goes back to
  Clock::time_point frame_start;       ///< when the current frame began
  Clock::time_point latency_pick;      ///< when the frame drawing the edited map took it up
  double orbit_cpu_start = 0;
  bool orbit_started = false;
  double idle_cpu_start = 0, idle_cpu_s = 0;
  int idle_frames = 0;
  std::vector<double> busy_frame_ms;  ///< UI frame times while the worker was busy
  // Progressive drawing (the window fills these in; the orbit phase waits for the full frame):
  bool view_fast = false;          ///< the 3-D view shown is the fast pass's
  std::vector<double> fast_ms;     ///< glFinish-timed fast frames of the orbit, ms
  std::size_t fast_instances = 0;  ///< ellipsoids the last fast frame drew
  std::size_t map_drawn = 0;       ///< height slice: ellipsoids the mirror holds (what the slice keeps)
  Clock::time_point last_move{};   ///< the orbit's last camera step
  double settle_ms = -1;           ///< the last orbit step until the full frame was shown
  /// The most labels cut in a frame after which the event loop, unscripted, would wait for input
  /// (the picture left on screen).
  int labels_cut_before_wait = 0;
};

/// What the script asks of the window that runs it, in the frame just drawn.
class ScriptWindow {
 public:
  virtual ~ScriptWindow() = default;
  /// The world point drawn at pixel (x, y) of the 3-D viewport (framebuffer pixels, top-left
  /// origin); nullopt where nothing is drawn.
  virtual std::optional<glm::vec3> pointUnder(float x_px, float y_px) = 0;
  /// Writes the window's picture as a PNG to `file`; the outcome goes to the status line.
  virtual void saveScreenshot(const std::string& file) = 0;
  /// Where the panels and the 3-D view are and where the map projects (the stats' "layout").
  virtual nlohmann::json layout() = 0;
  /// Queues `key` (a --press key) as if typed.
  virtual void press(int key) = 0;
};

/// The frame a script step follows: the snapshots it drew and what the window is still doing.
struct ScriptFrame {
  std::shared_ptr<const MappingSnapshot> mapping;  ///< null while nothing is open
  std::shared_ptr<const GlobalSnapshot> global;
  bool preparing = false;  ///< the preparation (rendering the built-in scene) still runs
  int settle_frames = 0;   ///< frames the UI still needs after input
};

/// Whether there is a script at all (a screenshot, figures or --exit asked for).
bool scripted(const ScriptRun& run);
/// A scripted run (--exit) fails on an error shown during the run; a user closing the window never does.
bool failedRun(const ScriptRun& run, const Workbench& bench);
/// Once the sequence is open: Play (--play-to-end), the keyframe selected (--keyframe) and the
/// query slice shown (--query-slice).
void startScript(const ScriptRun& run, Workbench& bench);
/// The UI frame starting at t0 / whose image is now on screen: the idle measurement's bookkeeping.
void scriptFrameStarts(ScriptRun& run, ScriptRun::Clock::time_point t0);
void scriptFrameShown(ScriptRun& run, ScriptRun::Clock::time_point t0);
/// One step of the script, after the frame is drawn (before it is swapped to the screen).
void advanceScript(ScriptRun& run, Workbench& bench, ScriptWindow& window, const ScriptFrame& frame);
/// Whether this frame is the one the script takes its screenshots of: the window then writes
/// the 3-D view's own image (--view-screenshot) after drawing the view and before the panels.
bool viewScreenshotDue(const ScriptRun& run, const Workbench& bench);

}  // namespace vdmap::app::gui
