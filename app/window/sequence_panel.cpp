#include "app/window/sequence_panel.h"

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui_stdlib.h>

#include "app/window/map_file_panel.h"
#include "app/window/widgets.h"
#include "mapping/core/message_text.h"
#include "mapping/core/timing.h"
#include "render/colormap.h"

namespace vdmap::app::gui {
namespace {

// Above the scrubber: a marker at every loop closure's frame, its figures in a tooltip. Markers
// closer than 0.8 em merge into one wider marker with their count (clusterMarkers); a click on
// one selects the newest loop's revisited keyframe.
void drawLoopStrip(Workbench& bench, const WindowState& win, int total) {
  const float font = ImGui::GetFontSize();
  const bool clicked =
      ImGui::InvisibleButton("##loops", {std::max(1.f, ImGui::GetContentRegionAvail().x), 0.75f * font});
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const ImU32 color = rgbColor(render::kLoopEdgeColor);
  const float mouse_x = ImGui::GetIO().MousePos.x;
  const std::vector<LoopEvent>& loops = win.mapping->loops;
  std::vector<float> xs;
  // Where the scrubber's grab stands at each loop's frame (the keyframe ticks' formula).
  for (const LoopEvent& e : loops)
    xs.push_back(lo.x + 6.f + (hi.x - lo.x - 12.f) * static_cast<float>(e.position) / std::max(1, total - 1));
  int revisited = -1;  // the newest loop of the marker under the mouse
  std::string hovered;
  for (const MarkerCluster& c : clusterMarkers(xs, 0.8f * font)) {
    const float left = xs[static_cast<std::size_t>(c.members.front())],
                right = xs[static_cast<std::size_t>(c.members.back())];
    const float half = 0.35f * font;
    draw->AddTriangleFilled({left - half, lo.y}, {right + half, lo.y}, {c.x, hi.y}, color);
    if (c.members.size() > 1) {
      char count[16];
      std::snprintf(count, sizeof count, "x%zu", c.members.size());
      draw->AddText({right + half + 2.f, lo.y - 0.15f * font}, color, count);
    }
    if (mouse_x < left - 0.5f * font || mouse_x > right + 0.5f * font) continue;
    constexpr std::size_t kListed = 10;
    const std::size_t n = c.members.size();
    for (std::size_t j = 0; j < std::min(n, kListed); ++j) {  // newest first
      const LoopEvent& e = loops[static_cast<std::size_t>(c.members[n - 1 - j])];
      char text[200];
      std::snprintf(text, sizeof text,
                    "%sloop closed at frame %d: K%d -> K%d, %d inliers, correction %s, pose graph %.1f ms",
                    hovered.empty() ? "" : "\n", e.position, e.loop.from, e.loop.to, e.loop.inliers,
                    metres(e.loop.correction_m).c_str(), e.loop.pose_graph_ms);
      hovered += text;
    }
    if (n > kListed) hovered += "\n... and " + std::to_string(n - kListed) + " earlier";
    hovered += "\nclick: select K" + std::to_string(loops[static_cast<std::size_t>(c.members.back())].loop.to) +
               " (the newest one's revisited keyframe)";
    revisited = loops[static_cast<std::size_t>(c.members.back())].loop.to;
  }
  if (clicked && revisited >= 0) bench.poses().selectKeyframe(revisited, true);
  tip(!hovered.empty() ? hovered
      : loops.empty()
          ? "Loop closures appear here (orange markers) when tracking re-observes a keyframe it is not linked to."
          : "Loop closures (markers closer than a character merge, with their count): hover over a marker for its "
            "frame, keyframes, correction and optimisation time; click it to select the revisited keyframe.");
}

void drawDepthScale(float width) {
  const float h = ImGui::GetFontSize() * 0.7f;
  const ImVec2 at = ImGui::GetCursorScreenPos();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  drawRamp(draw, at, width, h);
  for (int m = 0; m <= 6; m += 2) {
    char text[8];
    std::snprintf(text, sizeof text, "%d m", m);
    const float w = ImGui::CalcTextSize(text).x;
    const float x = std::clamp(width * m / 6.f - w / 2, 0.f, width - w);
    draw->AddText({at.x + x, at.y + h + 1}, IM_COL32(220, 220, 220, 255), text);
  }
  ImGui::Dummy({width, h + ImGui::GetFontSize() + 2});
  tip("Depth colours: viridis from 0 m (dark) to 6 m (yellow) and beyond; black: no measurement.");
}

void drawTimes(WindowState& win, float width) {
  std::vector<float> total_ms;
  std::vector<double> features, tracking, decision, update;
  const std::size_t n = win.mapping->times.size(), first = n > 200 ? n - 200 : 0;
  for (std::size_t i = first; i < n; ++i) {
    const StageTimes& t = win.mapping->times[i];
    total_ms.push_back(static_cast<float>(t.total_ms));
    features.push_back(t.features_ms);
    tracking.push_back(t.tracking_ms);
    decision.push_back(t.decision_ms);
    update.push_back(t.update_ms);
  }
  if (total_ms.empty()) return;
  char overlay[64];
  std::snprintf(overlay, sizeof overlay, "median %.1f ms", median({total_ms.begin(), total_ms.end()}));
  ImGui::PlotLines("##times", total_ms.data(), static_cast<int>(total_ms.size()), 0, overlay, 0.f, FLT_MAX,
                   {width, ImGui::GetFontSize() * 4.5f});
  tip("Mapping time of each of the last 200 frames (features, tracking with --poses track, keyframe decision and "
      "local-map update), ms.");
  if (beginRows("times")) {
    const auto row = [&](const char* name, const char* help, double ms) {
      label(win.check, name, help);
      ImGui::Text("%.1f ms", ms);
    };
    row("features", "ORB detection and the depth under each keypoint, median per frame (docs/method.md 5).",
        median(features));
    if (win.mapping->mapper.poses == PoseSource::kTrack)
      row("tracking",
          "The frame's pose against the current keyframe: matches by projection (or brute force and PnP "
          "RANSAC), then the dense refinement against its local map; relocalisation when weak. Median per frame.",
          median(tracking));
    row("keyframe decision",
        "Covisibility with the current keyframe, the revisit search and new edges, median per frame.",
        median(decision));
    row("local-map update",
        "Integrating the frame's depth into the keyframe's container (docs/method.md 2), median per frame.",
        median(update));
    ImGui::EndTable();
  }
}

// The sequence's folder, camera and frames, or the saved session's.
void drawWhatIsOpen(Workbench& bench, const WindowState& win) {
  const MappingSnapshot& mapping = *win.mapping;
  const int total = mapping.frames_total;
  if (const Sequence* sequence = bench.sequence()) {
    textWrapped(sequence->folder().string());
    ImGui::TextWrapped("%s; camera %s (%dx%d), %s", sequenceKindName(sequence->kind()).c_str(),
                       sequence->cameraSource().c_str(), mapping.camera.width, mapping.camera.height,
                       counted(total, "frame").c_str());
    std::string why = "What kind of sequence it is (it " + sequence->kindReason() +
                      "), where the intrinsics come "
                      "from (--camera, a camera file, a preset, a recording's camera_info), the image size in pixels, "
                      "and the frames selected.";
    for (const std::string& note : sequence->notes()) why += "\n" + note;
    tip(why);
  } else if (const StaticMap* file = bench.staticMap()) {  // opening files: a map file
    textWrapped(file->path.string());
    ImGui::TextWrapped("%s: %s, %s", mapFileKindName(file->kind),
                       counted(static_cast<long long>(file->ellipsoids.size()), "ellipsoid").c_str(),
                       counted(static_cast<long long>(mapping.keyframes.size()), "keyframe").c_str());
    tip("A map read whole from a file: nothing to play, re-map or rebuild (the Map panel shows its figures).");
  } else {
    textWrapped(bench.ui().settings.last_sequence);
    ImGui::TextWrapped("saved session: %s mapped, %s", counted(total, "frame").c_str(),
                       counted(static_cast<long long>(mapping.keyframes.size()), "keyframe").c_str());
    tip("A .vdmap file: the keyframes with their local maps, poses and covisibility graph, and the parameters "
        "they were mapped with (the Re-run parameters show them).");
    if (!bench.files().whyPlayerOff().empty()) textWrapped(bench.files().whyPlayerOff());
  }
}

// Play or Pause, Step, Back, Next keyframe and the fps limit. why_saved: why none can act ("" when
// they can).
void drawPlayer(Workbench& bench, WindowState& win, const PlayerStatus& status, const std::string& why_saved) {
  const bool saved = !why_saved.empty();
  const int total = win.mapping->frames_total;
  // Play, Step and Next keyframe cannot act once every frame is asked for (Pause still can).
  const bool at_end = status.target >= total;
  const std::string why_end =
      (total == 1 ? std::string("The one frame is mapped") : "All " + std::to_string(total) + " frames are mapped") +
      ": Back (Left) or the scrubber go back.";
  ImGui::BeginDisabled(at_end && !status.playing);
  if (ImGui::Button(status.playing ? "Pause" : "Play")) bench.key(KeyAction::kPlayPause);
  tip(saved                       ? why_saved
      : at_end && !status.playing ? why_end
                                  : "Maps the frames one after another up to the end (Space).");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(at_end);
  if (ImGui::Button("Step")) bench.key(KeyAction::kStepForward);
  tip(saved ? why_saved : at_end ? why_end : "Maps one more frame (Right).");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(status.target < 2);
  if (ImGui::Button("Back")) bench.key(KeyAction::kStepBack);
  tip(saved               ? why_saved
      : status.target < 2 ? "Nothing to go back to: fewer than two frames mapped."
                          : "One frame back (Left): the map is rebuilt from the first frame.");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(at_end);
  if (ImGui::Button("Next keyframe")) bench.key(KeyAction::kNextKeyframe);
  tip(saved ? why_saved : at_end ? why_end : "Maps up to the next frame that starts a keyframe (K).");
  ImGui::EndDisabled();
  checkFits(win.check);
  if (beginRows("player")) {
    UiState& ui = bench.ui();
    label(win.check, "fps limit", "Playback speed limit in frames per second; 0: as fast as mapping goes.");
    if (ImGui::SliderFloat("##fps", &ui.settings.play_fps, 0.f, 60.f, ui.settings.play_fps > 0 ? "%.0f" : "max"))
      bench.player().setFps(ui.settings.play_fps);
    ImGui::EndTable();
  }
}

// The scrubber, with a tick under it at every keyframe's first frame.
void drawScrubber(Workbench& bench, WindowState& win, const std::string& why_saved) {
  const int total = win.mapping->frames_total, mapped = win.mapping->frames_mapped;
  if (!win.scrubbing) win.scrub = std::max(0, mapped - 1);
  ImGui::SetNextItemWidth(-FLT_MIN);
  ImGui::SliderInt("##frame", &win.scrub, 0, std::max(0, total - 1), "frame %d");
  win.scrubbing = ImGui::IsItemActive();
  if (ImGui::IsItemDeactivatedAfterEdit()) bench.player().seek(win.scrub);
  tip(!why_saved.empty()
          ? why_saved
          : "Drag to a frame: forward maps up to it, backward re-maps from the start. Ticks: keyframes.");
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  for (const KeyframeInfo& k : win.mapping->keyframes) {
    const float x = lo.x + 6.f + (hi.x - lo.x - 12.f) * static_cast<float>(k.frame) / std::max(1, total - 1);
    draw->AddLine({x, hi.y - 5}, {x, hi.y}, IM_COL32(255, 220, 0, 255), 2.f);
  }
}

// The last mapped frame's colour and depth images (while a sequence plays), the depth scale and
// the stage times.
void drawFrameImages(const render::MapMirror& mirror, WindowState& win, bool show_images) {
  const float image_width = ImGui::GetContentRegionAvail().x;
  if (!show_images) return drawTimes(win, image_width);
  // The two images take what the panel has left above the depth scale and the stage times
  // (their height as drawn last frame), so the whole panel shows without scrolling (at
  // 1280x720 too); they keep their aspect and at least a third of the panel's width.
  const float each_h =
      (ImGui::GetContentRegionAvail().y - win.below_images_px - 2 * ImGui::GetStyle().ItemSpacing.y) / 2;
  const auto imageSize = [&](const render::Texture2D& t) {  // centred when narrower than the panel
    const float aspect = static_cast<float>(t.height()) / std::max(1, t.width());
    const float w = std::clamp(each_h / aspect, image_width / 3, image_width);
    ImGui::SetCursorPosX(ImGui::GetCursorPosX() + (image_width - w) / 2);
    return ImVec2{w, w * aspect};
  };
  const render::Texture2D& rgb = mirror.rgbTexture();
  ImGui::Image(textureId(rgb), imageSize(rgb));
  tip("The last mapped frame's colour image.");
  const render::Texture2D& depth = mirror.depthTexture();
  ImGui::Image(textureId(depth), imageSize(depth));
  tip("Its depth image: distance along the optical axis, black where the sensor measured nothing.");
  const float top = ImGui::GetCursorPosY();
  drawDepthScale(image_width);
  drawTimes(win, image_width);
  win.below_images_px = ImGui::GetCursorPosY() - top;
}

}  // namespace

void drawSequencePanel(Workbench& bench, const render::MapMirror& mirror, WindowState& win) {
  beginPanel("Sequence", win.layout.left, win.layout.left_w, win.layout.last_size.x);
  drawOpenArea(bench, win);  // opening files: map_file_panel.cpp
  // The first start: the built-in scene opens once it is rendered ("rendering the built-in scene").
  if (!bench.isOpen() && win.preparing) {
    std::string what = win.prepare_what;
    if (!what.empty()) what[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(what[0])));
    textWrapped(what + ": " + std::to_string(win.prepare_done) + " of " + std::to_string(win.prepare_total) +
                " frames, then it opens (the first start only: later starts reuse it).");
    ImGui::End();
    return;
  }
  if (!bench.isOpen()) {
    ImGui::TextWrapped("Nothing open: type a TUM RGB-D folder, a .vdmap session or a map file (map folder, PLY, "
                       "OctoMap) above, or drop one on the window.");
    ImGui::End();
    return;
  }
  const PlayerStatus status = bench.player().status();
  const int total = win.mapping->frames_total, mapped = win.mapping->frames_mapped;
  const bool saved = bench.savedSession();
  drawWhatIsOpen(bench, win);
  const std::string why_saved = !saved              ? ""
                                : bench.staticMap() ? std::string("A map file: ") + kStaticMapWhy + "."
                                : bench.files().whyPlayerOff().empty()
                                    ? "A saved session has its keyframes but no sequence to play or re-map."
                                    : "A saved session: " + bench.files().whyPlayerOff() + ".";
  if (bench.staticMap()) return ImGui::End();  // a map file: nothing to play (opening files)
  ImGui::BeginDisabled(saved);
  drawPlayer(bench, win, status, why_saved);
  if (win.mapping->mapper.poses == PoseSource::kTrack) drawLoopStrip(bench, win, total);
  drawScrubber(bench, win, why_saved);
  ImGui::EndDisabled();
  // The short form where the long one would be cut (a narrow panel while working).
  const char* working = status.busy ? " (working)" : "";
  const std::string keyframes = counted(static_cast<long long>(win.mapping->keyframes.size()), "keyframe");
  std::string counts = std::to_string(mapped) + " / " + counted(total, "frame") + " mapped, " + keyframes + working;
  if (ImGui::CalcTextSize(counts.c_str()).x > ImGui::GetContentRegionAvail().x)
    counts = std::to_string(mapped) + "/" + counted(total, "frame") + ", " + keyframes + working;
  ImGui::TextUnformatted(counts.c_str());
  checkFits(win.check);
  tip("Frames integrated into the keyframes' local maps so far, of the sequence's (or --frames') total, and the "
      "keyframes they made (docs/method.md 5: a new one when a frame re-observes under tau of the current one's features).");
  drawFrameImages(mirror, win, !mirror.rgbTexture().empty() && mapped > 0 && !saved);
  ImGui::End();
}

}  // namespace vdmap::app::gui
