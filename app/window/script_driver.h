#pragma once
// The scripted run (--play-to-end, --screenshot, --stats, --exit ...): once mapping and map
// building are done, reset the view, draw a few frames, take the screenshot, then the
// measurements asked for (slider-to-map latency, orbit frame time, idle CPU), then write the
// figures. The window calls advanceScript once per drawn frame.
#include <chrono>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/window/window_state.h"
#include "app/window/workbench_window.h"

namespace vdmap::app::gui {

enum class ScriptPhase { kWaitDone, kSettle, kLatency, kOrbit, kIdle, kFinish, kDone };

/// The script's options and its progress through them.
struct ScriptRun {
  using Clock = std::chrono::steady_clock;
  ScriptOptions options;
  ScriptPhase phase = ScriptPhase::kWaitDone;
  int countdown = 0;               ///< frames to draw before the screenshot
  bool finished = false;           ///< done, and the window should close (options.exit)
  bool screenshot_taken = false;   ///< by the script, so a failure removes it (and no older file)
  bool view_files_taken = false;   ///< --save-view / --view-screenshot, likewise
  nlohmann::json layout = nlohmann::json::object();  ///< recordLayout's figures
  nlohmann::json measure;          ///< --measure's points and distance (null: none asked or found)
  nlohmann::json probe;            ///< --probe's answer (null: none asked)
  int latency_generation = -1;     ///< the global map an edit waits to replace (-1: no edit pending)
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
  bool view_fast = false;            ///< the 3-D view shown is the fast pass's
  std::vector<double> fast_ms;       ///< glFinish-timed fast frames of the orbit, ms
  std::size_t fast_instances = 0;    ///< ellipsoids the last fast frame drew
  std::size_t map_drawn = 0;         ///< height slice: ellipsoids the mirror holds (what the slice keeps)
  Clock::time_point last_move{};     ///< the orbit's last camera step
  double settle_ms = -1;             ///< the last orbit step until the full frame was shown
  /// The most labels cut in a frame after which the event loop, unscripted, would wait for input
  /// (the picture left on screen).
  int labels_cut_before_wait = 0;
};

/// Whether there is a script at all (a screenshot, figures or --exit asked for).
bool scripted(const ScriptRun& run);
/// A scripted run (--exit) fails on an error shown during the run; a user closing the window never does.
bool failedRun(const ScriptRun& run, const Workbench& bench);
/// The process's CPU time (all threads), seconds.
double processCpuSeconds();
/// The UI frame starting at t0 / whose image is now on screen: the idle measurement's bookkeeping.
void scriptFrameStarts(ScriptRun& run, ScriptRun::Clock::time_point t0);
void scriptFrameShown(ScriptRun& run, ScriptRun::Clock::time_point t0);
/// One step of the script, after the frame is drawn (before it is swapped to the screen).
/// `keys`: the --press keys go there, as if typed; `settle_frames`: frames ImGui still needs
/// after input.
void advanceScript(ScriptRun& run, Workbench& bench, const render::Gl& gl, const WindowState& win, KeyQueue& keys,
                   int settle_frames);
/// Writes the window's back buffer as a PNG to `file`; the outcome goes to the status line.
void saveScreenshot(Workbench& bench, const render::Gl& gl, const WindowState& win, const std::string& file);
/// Whether this frame is the one the script takes its screenshots of: the window then calls
/// saveViewScreenshot after drawing the 3-D view and before drawing the panels over it.
bool viewScreenshotDue(const ScriptRun& run, const Workbench& bench);
/// Writes the 3-D view's own image (ViewController::spec's view: the viewport, the letterbox of a
/// keyframe view, or the container drawn with the view's layers) as a PNG to `file`, read from
/// the back buffer after the map is drawn and before ImGui draws; the outcome goes to the status
/// line.
void saveViewScreenshot(Workbench& bench, const render::Gl& gl, render::MapMirror& mirror, const WindowState& win,
                        const std::string& file);

}  // namespace vdmap::app::gui
