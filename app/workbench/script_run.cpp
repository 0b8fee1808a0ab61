#include "app/workbench/script_run.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>

#include "app/cli/error_text.h"
#include "app/workbench/figures.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/message_text.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"

namespace vdmap::app::gui {
namespace {

using Clock = ScriptRun::Clock;

// --- Latency (global map stream): one slider change at a time, from the edit until the first
// frame that draws the map built with it (what is still busy afterwards, such as the inspector's
// selection, is not the map's latency). The edits go through the live parameters, each to
// another value and back (merge distance first), so 2 x 10 runs time every one of them.
struct LatencyEdit {
  const char* key;
  double other;  // the value edited to; the edit after it goes back
};
constexpr LatencyEdit kLatencyEdits[] = {
    {"merge_distance", 0.2},   {"fusion_max_distance", 0.7}, {"occlusion_distance", 0.4}, {"occlusion_angle", 25},
    {"tau_group", 0.15},       {"filter_sigma_factor", 2.5}, {"min_points", 8},           {"occlusion_removal", 0},
    {"fuse_across_groups", 0}, {"sensor_model", 1},
};

// The process's CPU time (all threads), seconds.
double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Returns true while runs remain.
bool measureLatency(ScriptRun& run, Workbench& bench, const std::shared_ptr<const GlobalSnapshot>& global) {
  if (!bench.isOpen() || !global) return false;
  if (run.latency_generation >= 0) {
    if (global->generation <= run.latency_generation) return true;
    // This frame draws the new map; it is timed once on screen (scriptFrameShown), from its start
    // or, when the map was published after the frame began, from then.
    const GlobalSnapshot& g = *global;
    run.latency_pick = std::max(run.frame_start, g.t_published);
    run.latency_stages.push_back(
        {{"parameter", kLatencyEdits[(run.latency_ms.size() / 2) % std::size(kLatencyEdits)].key},
         {"edit", msBetween(run.latency_start, g.t_edit)},
         {"queue", msBetween(g.t_edit, g.t_build_start)},
         {"build", msBetween(g.t_build_start, g.t_build_end)},
         {"after_build", msBetween(g.t_build_end, g.t_published)},
         {"to_ui", msBetween(g.t_published, run.latency_pick)},
         {"t_g", 1e3 * g.map.t_g_s},
         {"t_g_parts", {g.map.groups_ms, g.map.merge_ms, g.map.occlusion_ms, g.map.fusion_ms}},
         {"reused",
          {g.map.reuse.groups, g.map.reuse.merged_groups, g.map.groups.size(), g.map.reuse.occlusion,
           g.map.reuse.fusion}}});
    run.latency_generation = -1;
    run.latency_shown_pending = true;
    return true;
  }
  if (run.latency_shown_pending) return true;  // until that frame is on screen
  if (static_cast<int>(run.latency_ms.size()) >= run.options.latency_runs) return false;
  if (bench.player().status().busy) return true;  // the previous build's follow-up work (the selection)
  const std::size_t i = run.latency_ms.size();
  const LatencyEdit& edit = kLatencyEdits[(i / 2) % std::size(kLatencyEdits)];
  const Parameter& p = *findParameter(edit.key);
  if (i % 2 == 0) run.latency_back = bench.parameters().inUse(p);
  run.latency_generation = global->generation;
  run.latency_start = Clock::now();
  bench.parameters().edit(p, i % 2 == 0 ? edit.other : run.latency_back);
  return true;
}
// --- end latency

// --edit KEY=VALUE: a live threshold edited as its slider does (a bad one goes to the status line,
// which fails the run).
void editScripted(Workbench& bench, const std::string& edit) {
  const std::size_t eq = edit.find('=');
  const Parameter* p = eq == std::string::npos ? nullptr : findParameter(edit.substr(0, eq));
  if (!p || !p->live) return bench.report(StatusLine::Kind::kError, "--edit: no threshold KEY=VALUE: " + edit);
  try {
    bench.parameters().edit(*p, parseValue(*p, edit.substr(eq + 1)));
  } catch (const std::exception& e) {
    bench.report(StatusLine::Kind::kError, std::string("--edit: ") + errorMessage(e));
  }
}

// --measure: the points under two pixels of the view as Ctrl+click finds them, from the depth
// of the frame just drawn (ImGui draws without the depth test, so the scene's depth is intact).
void measureScripted(ScriptRun& run, Workbench& bench, ScriptWindow& window) {
  const std::vector<float>& m = run.options.measure;
  const auto a = window.pointUnder(m[0], m[1]), b = window.pointUnder(m[2], m[3]);
  if (!a || !b) {
    bench.report(StatusLine::Kind::kError,
                 std::string("--measure: nothing drawn under pixel ") +
                     (a ? shortNumber(m[2]) + "," + shortNumber(m[3]) : shortNumber(m[0]) + "," + shortNumber(m[1])));
    return;
  }
  bench.view().addMeasurePoint(*a);
  bench.view().addMeasurePoint(*b);
  run.measure = {{"a", {a->x, a->y, a->z}}, {"b", {b->x, b->y, b->z}}, {"distance_m", glm::length(*b - *a)}};
}

// --probe: the point queries' probe under a pixel of the view, as the mouse there with Q on finds
// it (from the depth of the frame just drawn, or on the query slice while it is shown).
void probeScripted(ScriptRun& run, Workbench& bench, ScriptWindow& window) {
  const std::vector<float>& at = run.options.probe;
  const UiState& ui = bench.ui();
  bench.queries().probeAt(at[0], at[1], ui.view_width, ui.view_height, window.pointUnder(at[0], at[1]));
  if (!ui.probe_result) {
    bench.report(StatusLine::Kind::kError, "--probe: nothing drawn under pixel " + shortNumber(at[0]) + "," +
                                               shortNumber(at[1]) + " (and no query slice there)");
    return;
  }
  const ProbeResult& r = *ui.probe_result;
  run.probe = {
      {"class", occupancyName(r.state.state)},
      {"p", r.state.p_occupied},
      {"distance_m", std::isfinite(r.distance.distance_m) ? nlohmann::json(r.distance.distance_m) : nlohmann::json()},
      {"point", {r.point.x, r.point.y, r.point.z}},
      {"on_slice", r.on_slice},
      {"keyframe", r.state.keyframe},
      {"ellipsoid", r.state.ellipsoid},
      {"generation", r.generation},
      {"query_us", r.query_us},
      {"note", r.note},
      {"text", r.text()}};
}

void writeStats(const ScriptRun& run, Workbench& bench, const ScriptFrame& frame, const std::string& file) {
  const auto& mapping = frame.mapping;
  const auto& global = frame.global;
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
    // Tracking error against ground truth (figures.h; tracked poses with ground truth only).
    if (const TrackingError e = trackingError(*mapping); e.valid) {
      stats["ate_rmse_m"] = e.ate_rmse_m;
      stats["rpe_frame_m"] = e.rpe_frame_m;
      stats["rpe_frame_deg"] = e.rpe_frame_deg;
      stats["rpe_second_m"] = e.rpe_second_m;
      stats["trajectory_matched"] = e.matched;
    }
  }
  if (global) {
    stats["sigma_e"] = global->map.sigma_e;
    stats["merged"] = global->map.merged;
    stats["sigma_e_prime"] = global->map.sigma_e_prime;
    stats["t_g_s"] = global->map.t_g_s;
    stats["merge_distance_m"] = global->params.merge_distance_m;
  }
  if (const MapDiff* diff = bench.view().diff())
    stats["edit_diff"] = {{"edit", diff->edit},
                          {"removed", diff->removed.size()},
                          {"added", diff->added_count},
                          {"shown", bench.view().shownDiff() != nullptr}};
  stats["ui_frames_while_busy"] = run.busy_frame_ms.size();
  stats["ui_frame_ms_median_while_busy"] = median(run.busy_frame_ms);
  stats["layout"] = run.layout;
  if (!run.measure.is_null()) stats["measure"] = run.measure;
  if (!run.probe.is_null()) stats["probe"] = run.probe;
  if (const auto slice = bench.queries().slice()) {
    stats["query_slice"] = {{"axis", render::querySliceAxisName(slice->spec.axis)},
                            {"offset_m", slice->spec.offset_m},
                            {"color", render::querySliceColorName(slice->spec.color)},
                            {"width", slice->plane.width},
                            {"height", slice->plane.height},
                            {"occupied", slice->occupied},
                            {"free", slice->free},
                            {"unknown", slice->unknown},
                            {"compute_ms", slice->compute_ms}};
  }
  if (const auto query = bench.queries().snapshot())
    stats["queries"] = {{"generation", query->generation},
                        {"build_ms", query->build_ms},
                        {"note", query->note},
                        {"keyframes", query->map->keyframes()},
                        {"ellipsoids", query->map->ellipsoids()},
                        {"memory_bytes", query->map->memoryBytes()}};
  stats["labels_cut_before_wait"] = run.labels_cut_before_wait;
  stats["show_help"] = ui.show_help;
  stats["view_from_keyframe"] = ui.view_from_keyframe;
  stats["map_drawn"] = run.map_drawn;  // height slice: the ellipsoids the 3-D view holds
  stats["show_before_optimisation"] = ui.show_before_optimisation;
  if (global) stats["map_before_optimisation"] = global->before_optimisation;
  // Latency (global map stream): per edit, the total and its stages (edit, queue, build,
  // after_build, to_ui, frame: what the frame showing the new map took, upload and draw).
  if (!run.latency_ms.empty()) {
    stats["slider_to_map_ms"] = run.latency_ms;
    stats["slider_to_map_stages_ms"] = run.latency_stages;
  }
  if (!run.orbit_ms.empty()) {
    stats["orbit_frame_ms"] = run.orbit_ms;
    stats["orbit_frame_cpu_ms"] = run.orbit_cpu_ms;  // process CPU (all of llvmpipe's threads), per frame
    // Progressive drawing: the fast frames' own (glFinish-timed) draw times, what they drew,
    // and the last orbit step until the full-quality frame was on screen.
    stats["orbit_fast_ms"] = run.fast_ms;
    stats["fast_instances"] = run.fast_instances;
    stats["settle_ms"] = run.settle_ms;
    stats["view_full_quality"] = !run.view_fast;
  }
  if (run.options.idle_seconds > 0) {
    stats["idle_cpu_s"] = run.idle_cpu_s;
    stats["idle_frames"] = run.idle_frames;  // UI frames drawn meanwhile
  }
  try {
    writeFileAtomically(file, jsonText(stats) + "\n");
  } catch (const std::exception& e) {
    bench.report(StatusLine::Kind::kError, errorMessage(e));
  }
}

}  // namespace

bool scripted(const ScriptRun& run) {
  const ScriptOptions& o = run.options;
  return !o.screenshot.empty() || !o.stats_json.empty() || !o.view_screenshot.empty() || !o.save_view.empty() ||
         o.view || o.exit;
}

bool failedRun(const ScriptRun& run, const Workbench& bench) { return run.options.exit && !bench.firstError().empty(); }

void startScript(const ScriptRun& run, Workbench& bench) {
  if (run.options.play_to_end) bench.player().play();
  if (run.options.keyframe >= 0) bench.poses().preselectKeyframe(run.options.keyframe);
  if (run.options.query_slice) {  // shown from the start (Queries section)
    bench.ui().settings.query_slice = true;
    bench.ui().settings.query_slice_spec = *run.options.query_slice;
  }
}

void scriptFrameStarts(ScriptRun& run, Clock::time_point t0) {
  run.frame_start = t0;  // latency: when the frame drawing a new map began
  if (run.phase == ScriptPhase::kIdle && t0 >= run.idle_until && run.idle_cpu_s == 0 && run.options.idle_seconds > 0)
    run.idle_cpu_s = processCpuSeconds() - run.idle_cpu_start;  // before this frame draws anything
}

void scriptFrameShown(ScriptRun& run, Clock::time_point t0) {
  if (run.latency_shown_pending) {  // latency: the first frame with the edited map is on screen
    run.latency_shown_pending = false;
    run.latency_ms.push_back(msSince(run.latency_start));
    run.latency_stages.back()["frame"] = msSince(run.latency_pick);
  }
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
void advanceScript(ScriptRun& run, Workbench& bench, ScriptWindow& window, const ScriptFrame& frame) {
  if (!scripted(run) || run.phase == ScriptPhase::kDone || frame.preparing) return;
  switch (run.phase) {
    case ScriptPhase::kWaitDone: {
      // Point queries asked for: on from the start, and built before the script goes on.
      const bool queries = !run.options.probe.empty() || run.options.query_slice;
      if (queries && bench.isOpen()) {
        UiState& ui = bench.ui();
        ui.settings.probe = ui.settings.probe || !run.options.probe.empty();
        if (run.options.query_slice && !ui.settings.query_slice)
          ui.settings.query_slice = true, ui.settings.query_slice_spec = *run.options.query_slice;
        const auto query = bench.queries().snapshot();
        const auto global = bench.global();
        if ((!query || !global || query->generation != global->generation) && bench.player().status().error.empty())
          return;
      }
      if (bench.isOpen()) {
        const PlayerStatus st = bench.player().status();
        const bool done =
            !st.busy && (st.target >= frame.mapping->frames_total || !run.options.play_to_end || !st.error.empty());
        if (!done) return;
      }
      if (run.options.view) bench.view().applySpec(*run.options.view);
      else bench.view().resetView();
      if (run.options.keyframe >= 0) bench.poses().selectKeyframe(run.options.keyframe);
      for (const std::string& edit : run.options.edit) editScripted(bench, edit);
      for (const int key : run.options.press) window.press(key);  // as if typed now
      for (const std::string& path : run.options.drop)
        bench.files().drop(path);  // as if dropped now (opened next frame)
      run.countdown = 3;           // frames to draw the final map before the screenshot
      run.phase = ScriptPhase::kSettle;
      return;
    }
    case ScriptPhase::kSettle:
      if (bench.player().status().busy) return;  // a key pressed above may have asked for a rebuild
      // A frame before the screenshot, so that it shows the measured line.
      if (run.countdown == 3 && run.options.query_slice) bench.queries().waitSlice();  // drawn by the next frames
      if (run.countdown == 2 && run.options.measure.size() == 4) measureScripted(run, bench, window);
      if (run.countdown == 2 && run.options.probe.size() == 2) probeScripted(run, bench, window);
      if (--run.countdown > 0) return;
      run.layout = window.layout();
      if (!run.options.screenshot.empty() && !failedRun(run, bench)) {
        window.saveScreenshot(run.options.screenshot);
        run.screenshot_taken = true;
      }
      if (run.options.view) bench.viewFiles().warnAboutSize(*run.options.view);
      if (!run.options.save_view.empty() && !failedRun(run, bench)) bench.viewFiles().save(run.options.save_view);
      run.view_files_taken = !run.options.save_view.empty() || !run.options.view_screenshot.empty();
      run.phase = ScriptPhase::kLatency;
      return;
    case ScriptPhase::kLatency:
      if (measureLatency(run, bench, frame.global)) return;
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
        bench.view().orbit(0.03f, 0.f);
        run.orbit_frame_start = run.last_move = Clock::now();
        run.orbit_cpu_start = cpu;
        return;
      }
      if (bench.player().status().busy || frame.settle_frames > 0) return;  // idle: the worker and the UI
      if (run.view_fast) return;       // the full-quality frame follows once the camera rests
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
      if (!failedRun(run, bench) && !run.options.stats_json.empty())
        writeStats(run, bench, frame, run.options.stats_json);
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

bool viewScreenshotDue(const ScriptRun& run, const Workbench& bench) {
  // advanceScript takes the screenshots in the frame whose settle countdown ends.
  return !run.options.view_screenshot.empty() && run.phase == ScriptPhase::kSettle && run.countdown == 1 &&
         !bench.player().status().busy && !failedRun(run, bench);
}

}  // namespace vdmap::app::gui
