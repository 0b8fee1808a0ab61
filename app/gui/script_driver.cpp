#include "app/gui/script_driver.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>

#include "app/timing.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"

namespace vdmap::app::gui {
namespace {

using Clock = ScriptRun::Clock;

nlohmann::json toJson(const Rect& r) { return {r.x, r.y, r.w, r.h}; }

// A --view-file view is drawn at the window's viewport, not at its own size: a size that differs
// gives another picture than `vdmap render --view-file` (another aspect), so say so.
void warnAboutTheViewsSize(Workbench& bench, const render::ViewSpec& asked) {
  const render::ViewSpec shown = bench.viewSpec();
  if (asked.width <= 0 || (asked.width == shown.width && asked.height == shown.height)) return;
  bench.report(StatusLine::Kind::kWarning, "the view file's view is " + std::to_string(asked.width) + "x" +
                                               std::to_string(asked.height) + ", the window's " + std::to_string(shown.width) +
                                               "x" + std::to_string(shown.height) + " (--window-size changes it)");
}

// One slider change at a time (merge distance, alternating): from the edit until the frame
// that shows the map built with it. Returns true while runs remain.
bool measureLatency(ScriptRun& run, Workbench& bench, const WindowState& win) {
  const auto& global = win.global;
  if (!bench.isOpen() || !global) return false;
  if (run.latency_generation >= 0) {
    if (global->generation <= run.latency_generation || bench.player().busy) return true;
    run.latency_ms.push_back(msSince(run.latency_start));  // this frame draws the new map
    run.latency_generation = -1;
  }
  if (static_cast<int>(run.latency_ms.size()) >= run.options.latency_runs) return false;
  const Parameter& p = *findParameter("merge_distance");
  run.latency_generation = global->generation;
  run.latency_start = Clock::now();
  bench.editParameter(p, run.latency_ms.size() % 2 == 0 ? 0.2 : GlobalMapParams{}.merge_distance_m);
  return true;
}

// Where the panels and the 3-D view are and where the map projects, for the stats file.
void recordLayout(ScriptRun& run, Workbench& bench, const WindowState& win) {
  const auto& global = win.global;
  UiState& ui = bench.ui();
  const Layout& at = win.layout;
  run.layout = {{"window", {at.fb_width, at.fb_height}},
                {"viewport", toJson(at.view)},
                {"panels", {{"Sequence", toJson(at.left)}, {"Map", toJson(at.right)}, {"Status", toJson(at.status)}}},
                {"labels_cut", win.check.labels_cut},
                {"help", toJson(at.help)},  // all zero while the help is closed
                {"up", {ui.camera.up.x, ui.camera.up.y, ui.camera.up.z}}};
  if (!global || global->map.ellipsoids.empty()) return;
  // What the view draws of the map (each ellipsoid's extent at the sigma, strays left out and
  // counted), so a cut is seen here.
  const render::DrawnBounds drawn = bench.drawnMap();
  run.layout["map_strays"] = drawn.strays;
  if (drawn.empty) return;
  const render::FrameBox box(drawn.lo, drawn.hi, drawn.axes);
  const ViewportView v = bench.view(ui.view_width, ui.view_height);
  float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (int c = 0; c < 8; ++c) {
    const glm::vec3 p = box.corner(c);
    const glm::vec4 q = v.camera.T_C_W * glm::vec4(p, 1.f);
    const float u = v.camera.fx * q.x / q.z + v.camera.cx + win.layout.view.x + v.image.x;
    const float w = v.camera.fy * q.y / q.z + v.camera.cy + win.layout.view.y + v.image.y;
    x0 = std::min(x0, u), y0 = std::min(y0, w), x1 = std::max(x1, u), y1 = std::max(y1, w);
  }
  run.layout["map_bbox_px"] = {x0, y0, x1, y1};
}

void writeStats(const ScriptRun& run, Workbench& bench, const WindowState& win, const std::string& file) {
  const auto& mapping = win.mapping;
  const auto& global = win.global;
  UiState& ui = bench.ui();
  nlohmann::json stats = {{"error", bench.firstError()}};
  if (mapping) {
    stats["frames_mapped"] = mapping->frames_mapped;
    stats["frames_total"] = mapping->frames_total;
    stats["keyframes"] = mapping->keyframes.size();
    stats["edges"] = mapping->edges.size();
    stats["cell_size_px"] = mapping->mapper.local_map.cell_size_px;
    stats["loop_closures"] = mapping->loops.size();
    stats["frames_lost"] = mapping->frames_lost;
    stats["frames_weak"] = mapping->frames_weak;
    stats["frames_relocalised"] = mapping->frames_relocalised;
    // The sequence has ground truth for the mapped frames, whether they were mapped with it or tracked.
    stats["has_groundtruth"] = mapping->frames_with_groundtruth > 0;
    stats["poses"] = mapping->mapper.poses == PoseSource::kTrack ? "track" : "gt";
  }
  if (global) {
    stats["sigma_e"] = global->map.sigma_e;
    stats["merged"] = global->map.merged;
    stats["sigma_e_prime"] = global->map.sigma_e_prime;
    stats["t_g_s"] = global->map.t_g_s;
    stats["merge_distance_m"] = global->params.merge_distance_m;
  }
  stats["ui_frames_while_busy"] = run.busy_frame_ms.size();
  stats["ui_frame_ms_median_while_busy"] = median(run.busy_frame_ms);
  stats["layout"] = run.layout;
  stats["labels_cut_before_wait"] = run.labels_cut_before_wait;
  stats["show_help"] = ui.show_help;
  stats["view_from_keyframe"] = ui.view_from_keyframe;
  stats["show_before_optimisation"] = ui.show_before_optimisation;
  if (global) stats["map_before_optimisation"] = global->before_optimisation;
  if (!run.latency_ms.empty()) stats["slider_to_map_ms"] = run.latency_ms;
  if (!run.orbit_ms.empty()) {
    stats["orbit_frame_ms"] = run.orbit_ms;
    stats["orbit_frame_cpu_ms"] = run.orbit_cpu_ms;  // process CPU (all of llvmpipe's threads), per frame
  }
  if (run.options.idle_seconds > 0) {
    stats["idle_cpu_s"] = run.idle_cpu_s;
    stats["idle_frames"] = run.idle_frames;  // UI frames drawn meanwhile
  }
  try {
    writeFileAtomically(file, jsonText(stats) + "\n");
  } catch (const std::exception& e) {
    bench.report(StatusLine::Kind::kError, e.what());
  }
}

}  // namespace

bool scripted(const ScriptRun& run) {
  const ScriptOptions& o = run.options;
  return !o.screenshot.empty() || !o.stats_json.empty() || !o.view_screenshot.empty() || !o.save_view.empty() ||
         o.view || o.exit;
}

bool failedRun(const ScriptRun& run, const Workbench& bench) { return run.options.exit && !bench.firstError().empty(); }

double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void scriptFrameStarts(ScriptRun& run, Clock::time_point t0) {
  if (run.phase == ScriptPhase::kIdle && t0 >= run.idle_until && run.idle_cpu_s == 0 && run.options.idle_seconds > 0)
    run.idle_cpu_s = processCpuSeconds() - run.idle_cpu_start;  // before this frame draws anything
}

void scriptFrameShown(ScriptRun& run, Clock::time_point t0) {
  if (run.phase != ScriptPhase::kIdle) return;
  if (run.idle_until == Clock::time_point::max()) {  // the measurement starts now
    run.idle_cpu_start = processCpuSeconds();
    const std::chrono::duration<double> idle(run.options.idle_seconds);
    run.idle_until = Clock::now() + std::chrono::duration_cast<Clock::duration>(idle);
  } else if (t0 < run.idle_until) {
    ++run.idle_frames;
  }
}

// Once mapping and map building are done: reset the view, draw a few frames, take the
// screenshot, then the measurements asked for, then the figures.
void advanceScript(ScriptRun& run, Workbench& bench, const render::Gl& gl, const WindowState& win, KeyQueue& keys,
                   int settle_frames) {
  if (!scripted(run) || run.phase == ScriptPhase::kDone || win.preparing) return;
  switch (run.phase) {
    case ScriptPhase::kWaitDone: {
      if (bench.isOpen()) {
        const PlayerStatus st = bench.player();
        const bool done =
            !st.busy && (st.target >= win.mapping->frames_total || !run.options.play_to_end || !st.error.empty());
        if (!done) return;
      }
      if (run.options.view) bench.applyViewSpec(*run.options.view);
      else bench.resetView();
      if (run.options.keyframe >= 0) bench.selectKeyframe(run.options.keyframe);
      for (const int key : run.options.press) keys.presses.emplace_back(key, 0);  // as if typed now
      run.countdown = 3;  // frames to draw the final map before the screenshot
      run.phase = ScriptPhase::kSettle;
      return;
    }
    case ScriptPhase::kSettle:
      if (bench.player().busy) return;  // a key pressed above may have asked for a rebuild
      if (--run.countdown > 0) return;
      recordLayout(run, bench, win);
      if (!run.options.screenshot.empty() && !failedRun(run, bench)) {
        saveScreenshot(bench, gl, win, run.options.screenshot);
        run.screenshot_taken = true;
      }
      if (run.options.view) warnAboutTheViewsSize(bench, *run.options.view);
      if (!run.options.save_view.empty() && !failedRun(run, bench)) bench.saveView(run.options.save_view);
      run.view_files_taken = !run.options.save_view.empty() || !run.options.view_screenshot.empty();
      run.phase = ScriptPhase::kLatency;
      return;
    case ScriptPhase::kLatency:
      if (measureLatency(run, bench, win)) return;
      run.phase = ScriptPhase::kOrbit;
      return;
    case ScriptPhase::kOrbit:
      if (static_cast<int>(run.orbit_ms.size()) < run.options.orbit_frames) {
        const double cpu = processCpuSeconds();
        if (run.orbit_started) {
          run.orbit_ms.push_back(msSince(run.orbit_frame_start));
          run.orbit_cpu_ms.push_back(1e3 * (cpu - run.orbit_cpu_start));
        }
        run.orbit_started = true;
        bench.orbit(0.03f, 0.f);
        run.orbit_frame_start = Clock::now();
        run.orbit_cpu_start = cpu;
        return;
      }
      if (bench.player().busy || settle_frames > 0) return;  // idle: the worker and the UI
      run.phase = ScriptPhase::kIdle;  // starts once this frame is on screen (scriptFrameShown)
      run.idle_until = Clock::time_point::max();
      return;
    case ScriptPhase::kIdle:
      if (Clock::now() < run.idle_until) return;
      run.phase = ScriptPhase::kFinish;
      return;
    case ScriptPhase::kFinish:
      // A failed scripted run (--exit with an error, e.g. a bad session) writes neither file:
      // a screenshot of the error would pass for a result. One taken before a
      // later failure is removed.
      if (!failedRun(run, bench) && !run.options.stats_json.empty()) writeStats(run, bench, win, run.options.stats_json);
      if (failedRun(run, bench) && run.screenshot_taken) {
        std::error_code ignored;
        std::filesystem::remove(run.options.screenshot, ignored);
      }
      if (failedRun(run, bench) && run.view_files_taken) {
        std::error_code ignored;
        for (const std::string* file : {&run.options.view_screenshot, &run.options.save_view})
          if (!file->empty()) std::filesystem::remove(*file, ignored);
      }
      run.finished = run.options.exit;
      run.phase = ScriptPhase::kDone;
      return;
    case ScriptPhase::kDone: return;
  }
}

void saveScreenshot(Workbench& bench, const render::Gl& gl, const WindowState& win, const std::string& file) {
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.ReadBuffer(GL_BACK);
  const cv::Mat image = render::readFramebufferRgb(gl, 0, 0, win.layout.fb_width, win.layout.fb_height);
  std::error_code ignored;
  const std::string path = std::filesystem::absolute(file, ignored).lexically_normal().string();
  try {
    render::writePng(path, image);
    bench.report(StatusLine::Kind::kSuccess, "screenshot written to " + path);
  } catch (const std::exception& e) {
    bench.report(StatusLine::Kind::kError, e.what());
  }
}

bool viewScreenshotDue(const ScriptRun& run, const Workbench& bench) {
  // advanceScript takes the screenshots in the frame whose settle countdown ends.
  return !run.options.view_screenshot.empty() && run.phase == ScriptPhase::kSettle && run.countdown == 1 &&
         !bench.player().busy && !failedRun(run, bench);
}

void saveViewScreenshot(Workbench& bench, const render::Gl& gl, render::MapMirror& mirror, const WindowState& win,
                        const std::string& file) {
  const render::ViewSpec spec = bench.viewSpec();
  cv::Mat image;
  const auto selection = bench.selection();
  if (spec.kind == render::ViewKind::kContainer && selection && selection->keyframe == spec.keyframe &&
      win.mirrored.decoded_rgb_for >= 0) {
    // The container as the view's layers draw it (the grid and the image bounds in GL, as
    // `vdmap render` draws them; the window shows its own zoom-aware outline instead): the
    // mirror's container drawn again with the view's style. The window's style comes back with
    // the next frame's syncMirror.
    const render::ContainerStyle style{.sigma = spec.sigma,
                                       .color = spec.color,
                                       .cell_size_px = win.mapping->mapper.local_map.cell_size_px,
                                       .show_grid = spec.layers.grid,
                                       .show_bounds = spec.layers.bounds};
    mirror.setContainer(win.mirrored.decoded_rgb_for, spec.keyframe, win.mirrored.decoded_rgb, win.mapping->camera,
                        selection->T_W_K, selection->local, style);
    image = mirror.containerImage().clone();
  } else if (spec.kind == render::ViewKind::kContainer) {
    image = cv::Mat();  // no container yet: the error below
  } else {
    // Where drawScene drew the view (GL counts rows from the bottom).
    const UiState& ui = bench.ui();
    const ImVec2 scale = ImGui::GetIO().DisplayFramebufferScale;
    const int vx = static_cast<int>(win.layout.view.x * scale.x), vw = ui.view_width, vh = ui.view_height;
    const int vy = win.layout.fb_height - static_cast<int>(win.layout.view.y * scale.y) - vh;
    const render::PixelRect r = bench.view(vw, vh).image;
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl.ReadBuffer(GL_BACK);
    image = render::readFramebufferRgb(gl, vx + r.x, vy + (vh - r.y - r.height), r.width, r.height);
  }
  std::error_code ignored;
  const std::string path = std::filesystem::absolute(file, ignored).lexically_normal().string();
  try {
    if (image.empty()) throw std::runtime_error("--view-screenshot: the view has no image yet");
    render::writePng(path, image);
    bench.report(StatusLine::Kind::kSuccess, "view screenshot written to " + path);
  } catch (const std::exception& e) {
    bench.report(StatusLine::Kind::kError, e.what());
  }
}

}  // namespace vdmap::app::gui
