// The Map panel's "Tracking and loop closures" section (tracked poses only).
#include <algorithm>
#include <cfloat>
#include <cstdio>

#include "app/window/map_sections.h"
#include "app/window/widgets.h"
#include "app/workbench/figures.h"
#include "mapping/core/message_text.h"

namespace vdmap::app::gui {
namespace {

// Tracked against true: ATE and RPE as the TUM RGB-D benchmark defines them (figures.h).
void drawTrackingError(WindowState& win) {
  const TrackingError e = trackingError(*win.mapping);
  if (!e.valid) return;
  if (beginRows("tracking error")) {
    label(win.check, "ATE rmse",
          "Absolute trajectory error (TUM RGB-D benchmark, Sturm et al. 2012): the tracked camera positions after the "
          "least-squares SE(3) alignment to the ground truth (Horn), rmse over the " +
              std::to_string(e.matched) +
              " frames both have (matched by timestamp). The gap drawn in the view is not aligned.");
    ImGui::TextUnformatted(metres(e.ate_rmse_m).c_str());
    label(win.check, "ATE median, max", "The same aligned position errors' median and largest.");
    ImGui::Text("%s, %s", metres(e.ate_median_m).c_str(), metres(e.ate_max_m).c_str());
    label(win.check, "RPE / frame",
          "Relative pose error (TUM RGB-D benchmark): the error of the motion between consecutive matched frames, "
          "rmse of its translation and rotation; the drift per frame, independent of the alignment.");
    ImGui::Text("%s, %.2f deg", metres(e.rpe_frame_m).c_str(), e.rpe_frame_deg);
    label(win.check, "RPE / second",
          "Relative pose error over frames 1 s apart (TUM RGB-D benchmark, delta = 1 s): the drift per second, rmse "
          "over " +
              std::to_string(e.rpe_second_pairs) + " pairs.");
    if (e.rpe_second_pairs > 0) ImGui::Text("%s, %.2f deg", metres(e.rpe_second_m).c_str(), e.rpe_second_deg);
    else ImGui::TextDisabled("under 1 s mapped");
    ImGui::EndTable();
  }
}

}  // namespace

void drawTracking(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  Settings& s = ui.settings;
  const bool truth = win.mapping->hasGroundTruth();
  const int placed = static_cast<int>(win.mapping->trajectory.size());
  swatch(render::kTrajectoryColor);
  ImGui::AlignTextToFramePadding();
  ImGui::Text("tracked: %s placed, %d lost", counted(placed, "frame").c_str(), win.mapping->frames_lost);
  tip("The camera trajectory vdmap estimated (blue), every placed frame at its pose relative to its keyframe, so "
      "it follows each correction. Lost frames could not be placed and were skipped, never integrated.");
  if (win.mapping->frames_weak + win.mapping->frames_relocalised > 0) {
    ImGui::Text("  %d relocalised, %d on a weak estimate", win.mapping->frames_relocalised, win.mapping->frames_weak);
    tip("Of the placed frames (of the whole run, a saved session's included): relocalised ones were placed against another keyframe "
        "when the current one gave no good estimate (a jump, a place seen again); weak ones on the current keyframe's "
        "estimate with either the features (PnP) or the dense refinement against its local map not trusted.");
  }
  swatch(render::kGroundTruthColor);
  ImGui::BeginDisabled(!truth);
  ImGui::Checkbox("ground truth", &s.show_groundtruth);
  tip(truth ? "The sequence's groundtruth.txt poses of the same frames (green), in the same world frame (the first "
              "frame anchors both), not aligned: the gap is the drift."
            : "The sequence has no groundtruth.txt poses for these frames.");
  ImGui::EndDisabled();
  drawTrackingError(win);
  swatch(render::kLoopEdgeColor);
  ImGui::AlignTextToFramePadding();
  ImGui::Text("%zu loop closures", win.mapping->loops.size());
  tip("Loop-closure edges between the two keyframes (orange; covisibility edges are viridis) and markers above the "
      "scrubber. After each loop the keyframe pose graph is optimised and the global map rebuilt.");
  const bool can = bench.poses().canShowBeforeOptimisation();
  ImGui::BeginDisabled(!can);
  bool before = ui.show_before_optimisation;
  if (ImGui::Checkbox("show before last optimisation (B)", &before)) bench.poses().showBeforeOptimisation(before);
  tip(!can ? "No pose-graph optimisation yet: it runs after a loop closure, and as the map refinement after the "
             "sequence's last frame."
           : "The keyframe poses, frustums, trajectory and global map as they were before the last pose-graph "
             "optimisation (a loop closure's, or the map refinement's after the last frame; rebuilt from the same "
             "local maps); off: after it. Pose edits and exports use the map after it.");
  ImGui::EndDisabled();
  checkFits(win.check);
  if (win.mapping->loops.empty()) return;
  const float rows = std::min(4.5f, static_cast<float>(win.mapping->loops.size()) + 0.5f);
  if (ImGui::BeginListBox("##loops", {-FLT_MIN, ImGui::GetTextLineHeightWithSpacing() * rows})) {
    for (std::size_t i = win.mapping->loops.size(); i-- > 0;) {  // newest first
      const LoopEvent& e = win.mapping->loops[i];
      char text[128];
      std::snprintf(text, sizeof text, "frame %d  K%d -> K%d  %s  %.1f ms##loop%zu", e.position, e.loop.from, e.loop.to,
                    metres(e.loop.correction_m).c_str(), e.loop.pose_graph_ms, i);
      if (ImGui::Selectable(text, ui.selected_keyframe == e.loop.to)) bench.poses().selectKeyframe(e.loop.to, true);
    }
    ImGui::EndListBox();
  }
  tip("Loop closures, newest first: the frame that closed it, the keyframe it was tracked in -> the keyframe it "
      "revisited, the largest keyframe move of the optimisation and its time. Click to select the revisited keyframe.");
}

}  // namespace vdmap::app::gui
