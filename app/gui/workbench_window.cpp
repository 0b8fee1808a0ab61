#include "app/gui/workbench_window.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <future>
#include <iostream>
#include <sstream>
#include <thread>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <imgui_stdlib.h>
#include <nlohmann/json.hpp>

#include <Eigen/Eigenvalues>

#include "app/gui/glfw_context.h"
#include "app/timing.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"
#include "render/colormap.h"
#include "render/map_mirror.h"

namespace vdmap::app::gui {
namespace {

using Clock = std::chrono::steady_clock;
constexpr float kBackground[3] = {0.13f, 0.13f, 0.15f};
constexpr float kLetterbox[3] = {0.05f, 0.05f, 0.06f};
const ImVec4 kPendingColor(1.f, 0.7f, 0.25f, 1.f);
const ImVec4 kKindColor[] = {{0.85f, 0.85f, 0.85f, 1}, {0.45f, 0.9f, 0.45f, 1}, {1.f, 0.8f, 0.3f, 1}, {1.f, 0.42f, 0.42f, 1}};

double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

ImTextureID textureId(const render::Texture2D& t) {
  return reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(t.id()));
}

ImU32 rgbColor(const glm::u8vec3& c) { return IM_COL32(c.r, c.g, c.b, 255); }

// A tooltip for the last item, shown also when it is disabled (then it says why).
void tip(const std::string& text) {
  if (text.empty() || !ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) return;
  ImGui::BeginTooltip();
  ImGui::PushTextWrapPos(ImGui::GetFontSize() * 32.f);
  ImGui::TextUnformatted(text.c_str());
  ImGui::PopTextWrapPos();
  ImGui::EndTooltip();
}

// A horizontal colour ramp (viridis) from (x, y) of size w x h into `draw`.
void drawRamp(ImDrawList* draw, ImVec2 at, float w, float h) {
  constexpr int kSteps = 32;
  for (int i = 0; i < kSteps; ++i) {
    const float x0 = at.x + w * i / kSteps, x1 = at.x + w * (i + 1) / kSteps;
    draw->AddRectFilled({x0, at.y}, {x1 + 0.5f, at.y + h}, rgbColor(render::colormap((i + 0.5f) / kSteps)));
  }
  draw->AddRect(at, {at.x + w, at.y + h}, IM_COL32(200, 200, 200, 160));
}

std::string metres(double m) {
  char text[32];
  if (m < 0.01) std::snprintf(text, sizeof text, "%.2f mm", m * 1e3);
  else if (m < 1.0) std::snprintf(text, sizeof text, "%.1f mm", m * 1e3);
  else std::snprintf(text, sizeof text, "%.2f m", m);
  return text;
}

// Keys pressed since the last UI frame, kept by GLFW's key callback so that a tap shorter than
// one frame is never lost (Dear ImGui 1.86 only keeps which keys are down at the frame's start).
struct KeyQueue {
  std::deque<std::pair<int, int>> presses;  // (GLFW key, modifiers)
  int events = 0;                           // any input at all since the last frame
};

KeyQueue& keyQueue(GLFWwindow* window) { return *static_cast<KeyQueue*>(glfwGetWindowUserPointer(window)); }

// Installed before Dear ImGui's, which chains to them.
void installInputCallbacks(GLFWwindow* window) {
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
    ++keyQueue(w).events;
    if (action == GLFW_PRESS || (action == GLFW_REPEAT && (key == GLFW_KEY_LEFT || key == GLFW_KEY_RIGHT)))
      keyQueue(w).presses.emplace_back(key, mods);
  });
  glfwSetCursorPosCallback(window, [](GLFWwindow* w, double, double) { ++keyQueue(w).events; });
  glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int, int, int) { ++keyQueue(w).events; });
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double) { ++keyQueue(w).events; });
  glfwSetCharCallback(window, [](GLFWwindow* w, unsigned) { ++keyQueue(w).events; });
  glfwSetWindowFocusCallback(window, [](GLFWwindow* w, int) { ++keyQueue(w).events; });
  glfwSetCursorEnterCallback(window, [](GLFWwindow* w, int) { ++keyQueue(w).events; });
  glfwSetFramebufferSizeCallback(window, [](GLFWwindow* w, int, int) { ++keyQueue(w).events; });
  glfwSetWindowRefreshCallback(window, [](GLFWwindow* w) { ++keyQueue(w).events; });
}

std::optional<KeyAction> actionOf(int key, int mods) {
  switch (key) {
    case GLFW_KEY_SPACE: return KeyAction::kPlayPause;
    case GLFW_KEY_RIGHT: return KeyAction::kStepForward;
    case GLFW_KEY_LEFT: return KeyAction::kStepBack;
    case GLFW_KEY_K: return KeyAction::kNextKeyframe;
    case GLFW_KEY_F: return KeyAction::kFrameMap;
    case GLFW_KEY_R: return KeyAction::kResetView;
    case GLFW_KEY_V: return KeyAction::kViewFromKeyframe;
    case GLFW_KEY_C: return KeyAction::kContainer;
    case GLFW_KEY_B: return KeyAction::kBeforeOptimisation;
    case GLFW_KEY_H:
    case GLFW_KEY_F1: return KeyAction::kHelp;
    case GLFW_KEY_ESCAPE: return KeyAction::kEscape;
    case GLFW_KEY_Z:
      if (mods & GLFW_MOD_CONTROL) return KeyAction::kUndo;
      return std::nullopt;
    default: return std::nullopt;
  }
}

struct Rect {
  float x = 0, y = 0, w = 0, h = 0;
  bool contains(ImVec2 p) const { return p.x >= x && p.y >= y && p.x < x + w && p.y < y + h; }
  nlohmann::json json() const { return {x, y, w, h}; }
};

class WorkbenchWindow {
 public:
  WorkbenchWindow(Workbench& bench, GlfwWindowContext& context, const ScriptOptions& script, Preparation prepare,
                  KeyQueue& keys)
      : bench_(bench), context_(context), gl_(context.gl()), script_(script), keys_(keys), mirror_(gl_) {
    bench_.setOnChange([] { glfwPostEmptyEvent(); });
    if (prepare.run) {
      prepare_what_ = prepare.what;
      prepare_args_ = prepare.args;
      auto progress = progress_;
      preparing_ = std::async(std::launch::async, [run = std::move(prepare.run), progress] {
        return run([progress](std::size_t done, std::size_t total) {
          progress->first = done;
          progress->second = total;
          glfwPostEmptyEvent();
        });
      });
    } else {
      startScript();
    }
  }

  ~WorkbenchWindow() {
    if (preparing_.valid()) preparing_.wait();
    bench_.setOnChange(nullptr);
  }

  // Waits for input, news from the worker or a deadline, and draws a frame only when something
  // may have changed: an idle window costs (almost) nothing. Returns false when it should close.
  bool step() {
    if (!needsFrame()) {
      glfwWaitEventsTimeout(waitSeconds());
      if (!needsFrame()) return !glfwWindowShouldClose(context_.window()) && !script_finished_;
    }
    glfwPollEvents();
    frame();
    return !glfwWindowShouldClose(context_.window()) && !script_finished_;
  }

  // Scripted runs (--exit) fail on an error shown during the run; a user closing the window never does.
  int exitCode() const { return failedRun() ? 1 : 0; }
  bool failedRun() const { return script_.exit && !bench_.firstError().empty(); }

 private:
  UiState& ui() { return bench_.ui(); }
  bool scripted() const { return !script_.screenshot.empty() || !script_.stats_json.empty() || script_.exit; }

  void startScript() {
    if (script_.play_to_end) bench_.play();
    if (script_.keyframe >= 0) bench_.preselectKeyframe(script_.keyframe);
  }

  // What the newest snapshots are, to notice news without drawing.
  struct Seen {
    int session = 0;
    const void *mapping = nullptr, *global = nullptr, *selection = nullptr;
    int status = -1;
    bool busy = false;
    bool operator==(const Seen&) const = default;
  };
  Seen seen() {
    Seen s;
    s.status = ui().status.serial;
    if (bench_.isOpen()) {
      s.session = bench_.sessionSerial();
      s.mapping = bench_.mapping().get();
      s.global = bench_.global().get();
      s.selection = bench_.selection().get();
      s.busy = bench_.player().busy;
    }
    return s;
  }

  bool needsFrame() {
    if (keys_.events > 0 || !keys_.presses.empty() || settle_frames_ > 0) return true;
    if (preparing_.valid()) return true;  // the progress bar (woken by the renderer's progress)
    if (scripted()) {
      if (script_phase_ == Phase::kSettle || script_phase_ == Phase::kOrbit || script_phase_ == Phase::kFinish) return true;
      if (script_phase_ == Phase::kLatency && latency_generation_ < 0) return true;  // the next edit
      if (script_phase_ == Phase::kIdle) return Clock::now() >= idle_until_;
    }
    const Seen now = seen();
    return !(now == last_seen_) || (scripted() && script_phase_ == Phase::kWaitDone && now.busy);
  }

  double waitSeconds() const {
    if (script_phase_ == Phase::kIdle) return std::max(0.0, std::chrono::duration<double>(idle_until_ - Clock::now()).count());
    if (preparing_.valid()) return 0.2;
    // The worker wakes the loop itself (Workbench::setOnChange); the timeout is a safety net.
    return 2.0;
  }

  void frame() {
    const auto t0 = Clock::now();
    if (script_phase_ == Phase::kIdle && t0 >= idle_until_ && idle_cpu_s_ == 0 && script_.idle_seconds > 0)
      idle_cpu_s_ = processCpuSeconds() - idle_cpu_start_;  // before this frame draws anything
    // ImGui shows hover and active states a frame late: after input, draw two more frames.
    settle_frames_ = keys_.events > 0 ? 2 : std::max(0, settle_frames_ - 1);
    keys_.events = 0;
    if (preparing_.valid() && preparing_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) finishPreparation();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    glfwGetFramebufferSize(context_.window(), &fb_width_, &fb_height_);
    layout();
    handleKeys();
    bench_.sync();
    mapping_ = bench_.mapping();
    global_ = bench_.global();
    syncMirror();
    labels_cut_ = 0;
    drawSequencePanel();
    drawMapPanel();
    drawStatusBar();
    drawViewOverlay();
    drawContainerWindow();
    drawHelp();
    handleMouse();
    ui().reset_layout = false;
    last_seen_ = seen();
    ImGui::Render();
    drawScene();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (!screenshot_request_.empty()) {
      saveScreenshot(screenshot_request_);
      screenshot_request_.clear();
    }
    advanceScript();
    glfwSwapBuffers(context_.window());
    frame_ms_ = msSince(t0);
    if (script_phase_ == Phase::kIdle) {
      if (idle_until_ == Clock::time_point::max()) {  // the measurement starts now
        idle_cpu_start_ = processCpuSeconds();
        idle_until_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(script_.idle_seconds));
      } else if (t0 < idle_until_) {
        ++idle_frames_;
      }
    }
    frame_times_.push_back(frame_ms_);
    if (frame_times_.size() > 30) frame_times_.pop_front();
    if (bench_.player().busy) busy_frame_ms_.push_back(frame_ms_);
  }

  void finishPreparation() {
    try {
      SequenceArgs args = prepare_args_;
      args.folder = preparing_.get();
      bench_.open(args);
    } catch (const std::exception& e) {
      bench_.report(StatusLine::Kind::kError, prepare_what_ + ": " + e.what());
    }
    startScript();
  }

  // --- layout ---------------------------------------------------------------------------------

  // Panels docked to the left and right edges, the status bar along the bottom and the 3-D
  // viewport between them; widths follow the window (the user may drag a panel's inner edge).
  void layout() {
    const ImVec2 size = ImGui::GetIO().DisplaySize;
    const float font = ImGui::GetFontSize();
    status_h_ = ImGui::GetFrameHeight() + 2.f * ImGui::GetStyle().WindowPadding.y;
    const float body_h = std::max(1.f, size.y - status_h_);
    const float default_left = std::clamp(0.25f * size.x, 24.f * font, 42.f * font);
    const float default_right = std::clamp(0.28f * size.x, 27.f * font, 46.f * font);
    if (ui().reset_layout || left_w_ <= 0 || size.x != last_size_.x) left_w_ = default_left;
    if (ui().reset_layout || right_w_ <= 0 || size.x != last_size_.x) right_w_ = default_right;
    // Keep at least a third of the width for the 3-D view.
    const float max_panels = size.x * 2.f / 3.f;
    if (left_w_ + right_w_ > max_panels) {
      const float k = max_panels / (left_w_ + right_w_);
      left_w_ *= k;
      right_w_ *= k;
    }
    last_size_ = size;
    left_ = {0, 0, left_w_, body_h};
    right_ = {size.x - right_w_, 0, right_w_, body_h};
    status_ = {0, body_h, size.x, status_h_};
    view_ = {left_w_, 0, std::max(1.f, size.x - left_w_ - right_w_), body_h};
    const ImVec2 scale = ImGui::GetIO().DisplayFramebufferScale;
    ui().view_width = std::max(1, static_cast<int>(view_.w * scale.x));
    ui().view_height = std::max(1, static_cast<int>(view_.h * scale.y));
  }

  // Opens a docked panel at r; r becomes where it is, width its width (the user may drag its
  // inner edge).
  void beginPanel(const char* name, Rect& r, float& width) {
    const float font = ImGui::GetFontSize();
    ImGui::SetNextWindowPos({r.x, r.y}, ImGuiCond_Always);
    ImGui::SetNextWindowSize({r.w, r.h}, ImGuiCond_Always);
    ImGui::SetNextWindowSizeConstraints({18.f * font, r.h}, {std::max(18.f * font, last_size_.x * 0.45f), r.h});
    ImGui::Begin(name, nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoBringToFrontOnFocus);
    const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
    if (size.x != r.w) width = size.x;  // dragged: next frame re-docks with the new width
    r = {pos.x, pos.y, size.x, size.y};
  }

  // A row of a two-column table: the label (never cut: its column fits the widest) and a
  // tooltip, then the widget fills the rest of the row.
  void label(const char* text, const std::string& help, bool pending = false) {
    ImGui::TableNextRow();
    ImGui::TableSetColumnIndex(0);
    ImGui::AlignTextToFramePadding();
    if (pending) ImGui::PushStyleColor(ImGuiCol_Text, kPendingColor);
    ImGui::TextUnformatted(text);
    if (pending) ImGui::PopStyleColor();
    checkFits();
    tip(help);
    ImGui::TableSetColumnIndex(1);
    ImGui::SetNextItemWidth(-FLT_MIN);
  }

  bool beginRows(const char* id) {
    if (!ImGui::BeginTable(id, 2, ImGuiTableFlags_SizingFixedFit)) return false;
    ImGui::TableSetupColumn("label", ImGuiTableColumnFlags_WidthFixed);
    ImGui::TableSetupColumn("value", ImGuiTableColumnFlags_WidthStretch);
    return true;
  }

  // Counts an item that does not fit in its window or table cell (the scripted stats report
  // it: every label and button must be readable at every window size).
  void checkFits() {
    if (ImGui::GetItemRectMax().x > ImGui::GetWindowPos().x + ImGui::GetWindowWidth() - 1.f) ++labels_cut_;
    else if (ImGui::GetItemRectMax().x > ImGui::GetCursorScreenPos().x + ImGui::GetContentRegionAvail().x + 1.f &&
             ImGui::GetContentRegionAvail().x > 0)
      ++labels_cut_;
  }

  // --- GPU mirror -------------------------------------------------------------------------------

  void syncMirror() {
    const Settings& s = ui().settings;
    mirror_.setStyle({.color = s.color,
                      .sigma = s.ellipsoid_sigma,
                      .ellipsoids = s.show_ellipsoids,
                      .frustums = s.show_frustums,
                      .graph = s.show_graph,
                      .trajectory = s.show_trajectory,
                      .groundtruth = s.show_groundtruth});
    if (!bench_.isOpen()) return;
    if (bench_.sessionSerial() != mirrored_session_) {  // generations restart with every session
      mirrored_session_ = bench_.sessionSerial();
      session_base_ += 1 << 20;
    }
    if (global_) mirror_.setMap(session_base_ + global_->generation, global_->map.ellipsoids);
    else mirror_.setMap(session_base_, {});
    const auto mapping = mapping_;
    mirror_.setFrame(session_base_ + mapping->generation, mapping->rgb, mapping->depth, mapping->camera.depth_scale);
    const auto scene = [&] { return bench_.graphScene(*mapping); };
    mirror_.setGraph(session_base_ + mapping->generation, ui().selected_keyframe, scene, ui().show_before_optimisation);
    mirror_.setHighlight(ui().picked);
    const auto selection = bench_.selection();
    if (selection && selection->keyframe < static_cast<int>(mapping->keyframes.size())) {
      const int id = selection->keyframe;
      const render::ContainerStyle style{.sigma = 2.f, .color = s.color, .cell_size_px = mapping->mapper.local_map.cell_size_px};
      if (id >= 0) {
        const KeyframeInfo& k = mapping->keyframes[static_cast<std::size_t>(id)];
        // Keyed by the selection and the keyframe's pose (a pose edit re-projects nothing in the
        // container, which lives in the keyframe frame, but the ellipsoids are in the world).
        // The keyframe image is held compressed: decode it once per selection, not per UI frame.
        const int generation = session_base_ + selection->serial;
        if (decoded_rgb_for_ != generation) decoded_rgb_ = k.rgb.decode(), decoded_rgb_for_ = generation;
        mirror_.setContainer(generation, id, decoded_rgb_, mapping->camera, selection->T_W_K, selection->local, style);
      } else {
        mirror_.setContainer(session_base_ + selection->serial, -1, {}, mapping->camera, Transform::Identity(), {}, style);
      }
    }
  }

  void drawScene() {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl_.Disable(GL_SCISSOR_TEST);
    gl_.Viewport(0, 0, fb_width_, fb_height_);
    gl_.ClearColor(kBackground[0], kBackground[1], kBackground[2], 1.f);
    gl_.ClearDepth(1.0);
    gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (!bench_.isOpen() || fb_width_ <= 0 || fb_height_ <= 0) return;
    const ImVec2 scale = ImGui::GetIO().DisplayFramebufferScale;
    const int vx = static_cast<int>(view_.x * scale.x), vw = ui().view_width, vh = ui().view_height;
    const int vy = fb_height_ - static_cast<int>(view_.y * scale.y) - vh;  // GL counts rows from the bottom
    const ViewportView v = bench_.view(vw, vh);
    const bool from_keyframe = ui().view_from_keyframe >= 0;
    if (from_keyframe) {  // the letterbox's bars
      gl_.Enable(GL_SCISSOR_TEST);
      gl_.Scissor(vx, vy, vw, vh);
      gl_.ClearColor(kLetterbox[0], kLetterbox[1], kLetterbox[2], 1.f);
      gl_.Clear(GL_COLOR_BUFFER_BIT);
      gl_.Disable(GL_SCISSOR_TEST);
    }
    gl_.Viewport(vx + v.image.x, vy + (vh - v.image.y - v.image.height), v.image.width, v.image.height);
    mirror_.draw(v.camera, !from_keyframe);
    gl_.Viewport(0, 0, fb_width_, fb_height_);
  }

  // --- input ----------------------------------------------------------------------------------

  void handleKeys() {
    const bool typing = ImGui::GetIO().WantTextInput;
    while (!keys_.presses.empty()) {
      const auto [key, mods] = keys_.presses.front();
      keys_.presses.pop_front();
      if (typing && key != GLFW_KEY_F1) continue;  // the key belongs to a text field
      if (const auto action = actionOf(key, mods)) bench_.key(*action);
    }
  }

  void handleMouse() {
    const ImGuiIO& io = ImGui::GetIO();
    if (!bench_.isOpen()) return;
    const bool over_view = view_.contains(io.MousePos) && !io.WantCaptureMouse;
    for (int b = 0; b < 3; ++b)
      if (ImGui::IsMouseClicked(b)) drag_in_view_[b] = over_view;
    const ImVec2 scale = io.DisplayFramebufferScale;
    if (drag_in_view_[0] && ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
      if (io.KeyShift) bench_.pan(io.MouseDelta.x * scale.x, io.MouseDelta.y * scale.y);
      else if (io.MouseDelta.x != 0 || io.MouseDelta.y != 0) bench_.orbit(-io.MouseDelta.x * 0.006f, io.MouseDelta.y * 0.006f);
    }
    for (int b : {1, 2})
      if (drag_in_view_[b] && ImGui::IsMouseDragging(b) && (io.MouseDelta.x != 0 || io.MouseDelta.y != 0))
        bench_.pan(io.MouseDelta.x * scale.x, io.MouseDelta.y * scale.y);
    if (over_view && io.MouseWheel != 0.f) bench_.zoom(io.MouseWheel);
    if (drag_in_view_[0] && ImGui::IsMouseReleased(ImGuiMouseButton_Left)) {
      const ImVec2 drag = ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0.f);
      if (drag.x * drag.x + drag.y * drag.y < 9.f && over_view)
        bench_.pick((io.MousePos.x - view_.x) * scale.x, (io.MousePos.y - view_.y) * scale.y, ui().view_width,
                    ui().view_height);
    }
  }

  // --- the left panel: sequence and player ------------------------------------------------------

  void drawSequencePanel() {
    beginPanel("Sequence", left_, left_w_);
    const float open_w = ImGui::CalcTextSize("Open").x + 2 * ImGui::GetStyle().FramePadding.x;
    ImGui::SetNextItemWidth(-open_w - ImGui::GetStyle().ItemSpacing.x);
    const bool enter = ImGui::InputText("##folder", &ui().sequence_text, ImGuiInputTextFlags_EnterReturnsTrue);
    tip("A TUM RGB-D folder (rgb.txt, depth.txt, groundtruth.txt) or a saved session (.vdmap).");
    ImGui::SameLine();
    ImGui::BeginDisabled(ui().sequence_text.empty());
    if (ImGui::Button("Open") || (enter && !ui().sequence_text.empty())) bench_.openPath(ui().sequence_text);
    tip(ui().sequence_text.empty() ? "Type a folder or a .vdmap file on the left first."
                                   : "Opens the folder or session typed on the left; errors show in the status line below.");
    ImGui::EndDisabled();
    if (!bench_.isOpen()) {
      ImGui::TextWrapped("Nothing open: type a TUM RGB-D folder or a .vdmap session above.");
      ImGui::End();
      return;
    }
    const PlayerStatus status = bench_.player();
    const int total = mapping_->frames_total, mapped = mapping_->frames_mapped;
    const bool saved = bench_.savedSession();
    if (const TumSequence* sequence = bench_.sequence()) {
      ImGui::TextWrapped("%s", sequence->folder().c_str());
      ImGui::TextWrapped("camera %s (%dx%d), %d frames", sequence->cameraSource().c_str(), mapping_->camera.width,
                         mapping_->camera.height, total);
      tip("Where the intrinsics come from (--camera, camera.yaml or a preset named by the folder), the image size "
          "in pixels, and the frames selected.");
    } else {
      ImGui::TextWrapped("%s", ui().settings.last_sequence.c_str());
      ImGui::TextWrapped("saved session: %d frames mapped, %zu keyframes", total, mapping_->keyframes.size());
      tip("A .vdmap file: the keyframes with their local maps, poses and covisibility graph, and the parameters "
          "they were mapped with (the Re-run parameters show them).");
    }
    const std::string why_saved = "A saved session has its keyframes but no sequence to play or re-map.";
    // Play, Step and Next keyframe cannot act once every frame is asked for (Pause still can).
    const bool at_end = status.target >= total;
    const std::string why_end = "All " + std::to_string(total) + " frames are mapped: Back (Left) or the scrubber go back.";
    ImGui::BeginDisabled(saved);
    ImGui::BeginDisabled(at_end && !status.playing);
    if (ImGui::Button(status.playing ? "Pause" : "Play")) bench_.key(KeyAction::kPlayPause);
    tip(saved ? why_saved : at_end && !status.playing ? why_end : "Maps the frames one after another up to the end (Space).");
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::BeginDisabled(at_end);
    if (ImGui::Button("Step")) bench_.key(KeyAction::kStepForward);
    tip(saved ? why_saved : at_end ? why_end : "Maps one more frame (Right).");
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::BeginDisabled(status.target < 2);
    if (ImGui::Button("Back")) bench_.key(KeyAction::kStepBack);
    tip(saved ? why_saved
        : status.target < 2 ? "Nothing to go back to: fewer than two frames mapped."
                            : "One frame back (Left): the map is rebuilt from the first frame.");
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::BeginDisabled(at_end);
    if (ImGui::Button("Next keyframe")) bench_.key(KeyAction::kNextKeyframe);
    tip(saved ? why_saved : at_end ? why_end : "Maps up to the next frame that starts a keyframe (K).");
    ImGui::EndDisabled();
    checkFits();
    if (beginRows("player")) {
      label("fps limit", "Playback speed limit in frames per second; 0: as fast as mapping goes.");
      if (ImGui::SliderFloat("##fps", &ui().settings.play_fps, 0.f, 60.f, ui().settings.play_fps > 0 ? "%.0f" : "max"))
        bench_.setFps(ui().settings.play_fps);
      ImGui::EndTable();
    }
    if (mapping_->mapper.poses == PoseSource::kTrack) drawLoopStrip(total);
    // The scrubber, with a tick under it at every keyframe's first frame.
    if (!scrubbing_) scrub_ = std::max(0, mapped - 1);
    ImGui::SetNextItemWidth(-FLT_MIN);
    ImGui::SliderInt("##frame", &scrub_, 0, std::max(0, total - 1), "frame %d");
    scrubbing_ = ImGui::IsItemActive();
    if (ImGui::IsItemDeactivatedAfterEdit()) bench_.seek(scrub_);
    tip(saved ? why_saved : "Drag to a frame: forward maps up to it, backward re-maps from the start. Ticks: keyframes.");
    const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
    ImDrawList* draw = ImGui::GetWindowDrawList();
    for (const KeyframeInfo& k : mapping_->keyframes) {
      const float x = lo.x + 6.f + (hi.x - lo.x - 12.f) * static_cast<float>(k.frame) / std::max(1, total - 1);
      draw->AddLine({x, hi.y - 5}, {x, hi.y}, IM_COL32(255, 220, 0, 255), 2.f);
    }
    ImGui::EndDisabled();
    ImGui::Text("%d / %d frames mapped, %zu keyframes%s", mapped, total, mapping_->keyframes.size(),
                status.busy ? " (working)" : "");
    checkFits();
    tip("Frames integrated into the keyframes' local maps so far, of the sequence's (or --frames') total, and the "
        "keyframes they made (SPEC 5: a new one when a frame re-observes under tau of the current one's features).");

    const float image_width = ImGui::GetContentRegionAvail().x;
    if (!mirror_.rgbTexture().empty() && mapped > 0 && !saved) {
      // The two images take what the panel has left above the depth scale and the stage times
      // (their height as drawn last frame), so the whole panel shows without scrolling (at
      // 1280x720 too); they keep their aspect and at least a third of the panel's width.
      const float each_h =
          (ImGui::GetContentRegionAvail().y - below_images_px_ - 2 * ImGui::GetStyle().ItemSpacing.y) / 2;
      const auto imageSize = [&](const render::Texture2D& t) {  // centred when narrower than the panel
        const float aspect = static_cast<float>(t.height()) / std::max(1, t.width());
        const float w = std::clamp(each_h / aspect, image_width / 3, image_width);
        ImGui::SetCursorPosX(ImGui::GetCursorPosX() + (image_width - w) / 2);
        return ImVec2{w, w * aspect};
      };
      const render::Texture2D& rgb = mirror_.rgbTexture();
      ImGui::Image(textureId(rgb), imageSize(rgb));
      tip("The last mapped frame's colour image.");
      const render::Texture2D& depth = mirror_.depthTexture();
      ImGui::Image(textureId(depth), imageSize(depth));
      tip("Its depth image: distance along the optical axis, black where the sensor measured nothing.");
      const float top = ImGui::GetCursorPosY();
      drawDepthScale(image_width);
      drawTimes(image_width);
      below_images_px_ = ImGui::GetCursorPosY() - top;
    } else {
      drawTimes(image_width);
    }
    ImGui::End();
  }

  // Above the scrubber: a marker at every loop closure's frame, its figures in a tooltip.
  void drawLoopStrip(int total) {
    const float font = ImGui::GetFontSize();
    const bool clicked = ImGui::InvisibleButton("##loops", {std::max(1.f, ImGui::GetContentRegionAvail().x), 0.75f * font});
    const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
    int revisited = -1;  // the keyframe of the loop under the mouse (the last one when several are)
    ImDrawList* draw = ImGui::GetWindowDrawList();
    const ImU32 color = rgbColor(render::kLoopEdgeColor);
    const float mouse_x = ImGui::GetIO().MousePos.x;
    std::string hovered;
    for (const LoopEvent& e : mapping_->loops) {
      // Where the scrubber's grab stands at that frame (the keyframe ticks' formula).
      const float x = lo.x + 6.f + (hi.x - lo.x - 12.f) * static_cast<float>(e.position) / std::max(1, total - 1);
      draw->AddTriangleFilled({x - 0.35f * font, lo.y}, {x + 0.35f * font, lo.y}, {x, hi.y}, color);
      if (std::abs(mouse_x - x) <= 0.5f * font) {
        char text[200];
        std::snprintf(text, sizeof text, "%sloop closed at frame %d: K%d -> K%d (revisited; click selects it), %d inliers, "
                      "correction %s, pose graph %.1f ms", hovered.empty() ? "" : "\n", e.position, e.loop.from, e.loop.to,
                      e.loop.inliers, metres(e.loop.correction_m).c_str(), e.loop.pose_graph_ms);
        hovered += text;
        revisited = e.loop.to;
      }
    }
    if (clicked && revisited >= 0) bench_.selectKeyframe(revisited);
    tip(!hovered.empty() ? hovered
        : mapping_->loops.empty()
            ? "Loop closures appear here (orange markers) when tracking re-observes a keyframe it is not linked to."
            : "Loop closures: hover over a marker for its frame, keyframes, correction and optimisation time; click "
              "it to select the revisited keyframe.");
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

  void drawTimes(float width) {
    std::vector<float> total_ms;
    std::vector<double> features, tracking, decision, update;
    const std::size_t n = mapping_->times.size(), first = n > 200 ? n - 200 : 0;
    for (std::size_t i = first; i < n; ++i) {
      const StageTimes& t = mapping_->times[i];
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
        label(name, help);
        ImGui::Text("%.1f ms", ms);
      };
      row("features", "ORB detection and the depth under each keypoint, median per frame (SPEC 5).", median(features));
      if (mapping_->mapper.poses == PoseSource::kTrack)
        row("tracking", "The frame's pose against the current keyframe: matches by projection (or brute force and PnP "
            "RANSAC), then the dense refinement against its local map; relocalisation when weak. Median per frame.",
            median(tracking));
      row("keyframe decision", "Covisibility with the current keyframe, the revisit search and new edges, median per frame.",
          median(decision));
      row("local-map update", "Integrating the frame's depth into the keyframe's container (SPEC 2), median per frame.",
          median(update));
      ImGui::EndTable();
    }
  }

  // --- the right panel: map, parameters, keyframes ---------------------------------------------

  void drawMapPanel() {
    beginPanel("Map", right_, right_w_);
    if (bench_.isOpen()) {
      if (section("Thresholds (live)", true)) drawThresholds();
      if (section("Re-run parameters")) drawRerun();
      if (mapping_->mapper.poses == PoseSource::kTrack && section("Tracking and loop closures", true)) drawTracking();
      if (section("View", true)) drawView();
      if (section("Keyframes", true)) drawKeyframes();
      if (section("Picked ellipsoid", true)) drawPicked();
      if (section("Pose correction")) drawPoseFile();
      if (section("Export and save")) drawExport();
    }
    if (section("Settings")) {
      if (ImGui::Button("Reset to defaults")) bench_.resetToDefaults();
      tip("Thresholds, re-run parameters and view options back to the defaults; panels back to their widths.");
      ImGui::TextWrapped("Saved on exit (what you changed only) to %s; the window layout to imgui.ini beside it.",
                         settingsPath().c_str());
    }
    ImGui::End();
  }

  // A collapsible section of a panel; a scripted layout check (--expand-sections) opens them all.
  bool section(const char* name, bool open_by_default = false) {
    if (script_.expand_sections) ImGui::SetNextItemOpen(true, ImGuiCond_Always);
    return ImGui::CollapsingHeader(name, open_by_default ? ImGuiTreeNodeFlags_DefaultOpen : 0);
  }

  // One parameter of the table as a slider, combo or checkbox.
  void parameterRow(const Parameter& p, bool disabled, const std::string& why_disabled) {
    const bool pending = bench_.pending(p);
    std::string help = std::string(p.help) + "\n\nvalid: " + validityText(p) + "; `vdmap map " + std::string(p.flag) +
                       "`, --set / settings.json " + (p.live ? "thresholds." : "rerun.") + std::string(p.key) + ".";
    if (pending)
      help += "\n\nPending: the map shown was made with " + formatValue(p, bench_.inUse(p)) +
              (p.live ? " (rebuilding)." : "; Re-run applies the edited value.");
    if (disabled) help = why_disabled + "\n\n" + help;
    const std::string text = std::string(p.label) + (p.unit.empty() ? "" : " (" + std::string(p.unit) + ")") + (pending ? " *" : "");
    label(text.c_str(), help, pending);
    ImGui::BeginDisabled(disabled);
    double v = p.get(ui().params);
    bool changed = false;
    const std::string id = "##" + std::string(p.key);
    switch (p.kind) {
      case Parameter::Kind::kBool: {
        bool b = v != 0;
        changed = ImGui::Checkbox(id.c_str(), &b);
        v = b;
        break;
      }
      case Parameter::Kind::kChoice: {
        int i = static_cast<int>(v);
        std::vector<const char*> names(p.choices.begin(), p.choices.end());
        changed = ImGui::Combo(id.c_str(), &i, names.data(), static_cast<int>(names.size()));
        v = i;
        break;
      }
      case Parameter::Kind::kInt:
      case Parameter::Kind::kReal: {
        const char* format = p.kind == Parameter::Kind::kInt ? "%.0f" : "%.3g";
        changed = ImGui::SliderScalar(id.c_str(), ImGuiDataType_Double, &v, &p.slider_lo, &p.slider_hi, format);
        if (p.kind == Parameter::Kind::kInt) v = std::round(v);
        break;
      }
    }
    tip(help);
    ImGui::EndDisabled();
    if (changed) bench_.editParameter(p, v);
  }

  void drawThresholds() {
    const bool occlusion_off = !ui().params.global.occlusion_removal;
    const bool fusion_off = !ui().params.global.fuse_across_groups;
    if (beginRows("thresholds")) {
      for (const Parameter& p : parameterTable()) {
        if (!p.live) continue;
        if (p.key == "fusion_max_distance") {
          parameterRow(p, fusion_off, "Fusion across groups is off: this has no effect.");
          continue;
        }
        const bool occlusion_param = p.key == "occlusion_distance" || p.key == "occlusion_angle";
        parameterRow(p, occlusion_param && occlusion_off, "Occlusion removal is off: this has no effect.");
      }
      ImGui::EndTable();
    }
    if (!global_) return ImGui::TextWrapped("No global map yet: play or step the sequence.");
    const GlobalMap& m = global_->map;
    std::size_t stored = 0;
    for (const KeyframeInfo& k : mapping_->keyframes) stored += k.ellipsoids;
    if (beginRows("stats")) {
      const auto row = [&](const char* name, const std::string& help, const char* format, auto... values) {
        label(name, help);
        ImGui::Text(format, values...);
      };
      row("local maps", "Ellipsoids stored in all keyframes' containers (one per touched cell), before filtering.", "%zu",
          stored);
      row("Sigma_e", "Sigma_e (SPEC 6.4): ellipsoids the filter keeps in the local maps (enough points, not longer "
                     "than k times the sensor model's expectation).",
          "%zu (%.0f%%)", m.sigma_e, 100.0 * m.sigma_e / std::max<std::size_t>(1, stored));
      row("merged", "After mean-shift merging within each merge group (SPEC 6.2), before occlusion removal.", "%zu",
          m.merged);
      row("fused", "Ellipsoids fused into a copy of the same surface from another merge group (SPEC 6.5).", "%zu",
          m.merged_across_groups);
      row("Sigma_e'", "Sigma_e' (SPEC 6.4): ellipsoids of the global map, after merging, occlusion removal and "
                      "fusion across groups.",
          "%zu", m.sigma_e_prime);
      row("merge groups", "Groups of a centre keyframe and its neighbours with edge weight >= tau_group (SPEC 6.1).",
          "%zu", m.groups.size());
      row("t_g", "t_g (SPEC 6.4): wall time of the global map build: grouping, merging, occlusion removal.",
          "%.3f s", m.t_g_s);
      row("of which", "Grouping, merging and occlusion removal, ms.", "%.0f / %.0f / %.0f ms", m.groups_ms, m.merge_ms,
          m.occlusion_ms);
      row("built from", "The frames mapped when this map was built (it is rebuilt now and then while playing).",
          "%d frames%s", global_->frames_mapped, bench_.player().busy ? ", rebuilding" : "");
      ImGui::EndTable();
    }
    if (stored > 0 && m.sigma_e * 20 < stored) {
      ImGui::PushStyleColor(ImGuiCol_Text, kKindColor[2]);
      ImGui::TextWrapped("The filter keeps only %.1f%% of the local maps' ellipsoids: raise the filter sigma factor k or "
                         "lower min points to keep more.",
                         100.0 * m.sigma_e / stored);
      ImGui::PopStyleColor();
    }
  }

  void drawRerun() {
    const bool saved = bench_.savedSession();
    const std::string why = "A saved session keeps the parameters it was mapped with: there is no sequence to re-map.";
    if (beginRows("rerun")) {
      for (const Parameter& p : parameterTable())
        if (!p.live) parameterRow(p, saved, why);
      ImGui::EndTable();
    }
    bool any_pending = false;
    for (const Parameter& p : parameterTable()) any_pending |= !p.live && bench_.pending(p);
    ImGui::BeginDisabled(saved || !any_pending);
    if (ImGui::Button("Re-run")) bench_.rerun();
    tip(saved ? why
              : any_pending ? "Re-maps the sequence from the first frame with the values marked * (up to the frame reached)."
                            : "Nothing to apply: the sliders show the parameters the map was made with.");
    ImGui::SameLine();
    if (ImGui::Button("Revert")) ui().params.mapper = mapping_->mapper;
    tip("Puts the sliders back to the parameters the map was made with.");
    ImGui::EndDisabled();
    if (any_pending) {
      ImGui::SameLine();
      ImGui::TextColored(kPendingColor, "* pending");
    }
  }

  void drawView() {
    Settings& s = ui().settings;
    if (beginRows("view")) {
      label("colour", "rgb: the surface colour; keyframe: the keyframe each ellipsoid came from (the key in the view); "
                      "uncertainty: the largest standard deviation; count: points merged into it (colour bars in the view).");
      int color = static_cast<int>(s.color);
      if (ImGui::Combo("##colour", &color, render::kColorModeNames.data(), static_cast<int>(render::kColorModeNames.size())))
        s.color = static_cast<render::ColorMode>(color);
      label("draw", "Ellipsoids as surfaces at sigma standard deviations, or their centres as points (faster).");
      int shape = s.show_ellipsoids ? 0 : 1;
      const char* shapes[] = {"ellipsoids", "centres"};
      if (ImGui::Combo("##shape", &shape, shapes, 2)) s.show_ellipsoids = shape == 0;
      label("sigma", "Ellipsoid surfaces drawn at this many standard deviations.");
      ImGui::BeginDisabled(!s.show_ellipsoids);
      ImGui::SliderFloat("##sigma", &s.ellipsoid_sigma, 0.5f, 4.f, "%.1f");
      tip(s.show_ellipsoids ? "" : "Only the centres are drawn.");
      ImGui::EndDisabled();
      label("up axis", "The world direction kept up on screen, the one the view orbits about. data: estimated from the "
                       "cameras (their mean image-up direction) refined by the floor's normals.");
      int up = static_cast<int>(s.up_axis);
      if (ImGui::Combo("##up", &up, kUpAxisNames, 4)) {
        s.up_axis = static_cast<UpAxis>(up);
        bench_.resetView();
      }
      label("show", "Keyframe frustums (yellow: current, white: selected, red: the camera now), covisibility edges "
                    "(viridis by weight) and the camera trajectory (blue).");
      ImGui::Checkbox("frustums", &s.show_frustums);
      ImGui::SameLine();
      ImGui::Checkbox("graph", &s.show_graph);
      ImGui::SameLine();
      ImGui::Checkbox("trajectory", &s.show_trajectory);
      checkFits();
      ImGui::EndTable();
    }
    if (ImGui::Button("Frame map (F)")) bench_.frameMap();
    tip("Fits the map in the view, keeping the direction; the view follows the map again as it grows.");
    ImGui::SameLine();
    if (ImGui::Button("Reset view (R)")) bench_.resetView();
    tip("The default view of the whole map from above, about the up axis; follows the map again.");
    ImGui::SameLine();
    if (ImGui::Button("Help (H)")) bench_.key(KeyAction::kHelp);
    checkFits();
    ImGui::BeginDisabled(screenshot_text_.empty());
    if (ImGui::Button("Screenshot")) screenshot_request_ = screenshot_text_;
    tip(screenshot_text_.empty() ? "Type a file name on the right first." : "Writes the whole window as a PNG to the file named on the right.");
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::SetNextItemWidth(-FLT_MIN);
    ImGui::InputText("##shot", &screenshot_text_);
  }

  // A colour swatch as wide as a short line, in the text's row.
  void swatch(const glm::u8vec3& color) {
    const float h = ImGui::GetTextLineHeight();
    const ImVec2 at = ImGui::GetCursorScreenPos();
    const float y = at.y + ImGui::GetStyle().FramePadding.y + 0.5f * h;
    ImGui::GetWindowDrawList()->AddLine({at.x, y}, {at.x + 1.4f * h, y}, rgbColor(color), 3.f);
    ImGui::Dummy({1.4f * h, ImGui::GetFrameHeight()});
    ImGui::SameLine();
  }

  void drawTracking() {
    Settings& s = ui().settings;
    const bool truth = mapping_->hasGroundTruth();
    const int placed = static_cast<int>(mapping_->trajectory.size());
    swatch(render::kTrajectoryColor);
    ImGui::AlignTextToFramePadding();
    ImGui::Text("tracked: %d frames placed, %d lost", placed, mapping_->frames_lost);
    tip("The camera trajectory vdmap estimated (blue), every placed frame at its pose relative to its keyframe, so "
        "it follows each correction. Lost frames could not be placed and were skipped, never integrated.");
    if (mapping_->frames_weak + mapping_->frames_relocalised > 0) {
      ImGui::Text("  %d relocalised, %d on a weak estimate", mapping_->frames_relocalised, mapping_->frames_weak);
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
    swatch(render::kLoopEdgeColor);
    ImGui::AlignTextToFramePadding();
    ImGui::Text("%zu loop closures", mapping_->loops.size());
    tip("Loop-closure edges between the two keyframes (orange; covisibility edges are viridis) and markers above the "
        "scrubber. After each loop the keyframe pose graph is optimised and the global map rebuilt.");
    const bool can = bench_.canShowBeforeOptimisation();
    ImGui::BeginDisabled(!can);
    bool before = ui().show_before_optimisation;
    if (ImGui::Checkbox("show before last optimisation (B)", &before)) bench_.showBeforeOptimisation(before);
    tip(!can ? "No pose-graph optimisation yet: it runs after a loop closure, and as the map refinement after the "
               "sequence's last frame."
             : "The keyframe poses, frustums, trajectory and global map as they were before the last pose-graph "
               "optimisation (a loop closure's, or the map refinement's after the last frame; rebuilt from the same "
               "local maps); off: after it. Pose edits and exports use the map after it.");
    ImGui::EndDisabled();
    checkFits();
    if (mapping_->loops.empty()) return;
    const float rows = std::min(4.5f, static_cast<float>(mapping_->loops.size()) + 0.5f);
    if (ImGui::BeginListBox("##loops", {-FLT_MIN, ImGui::GetTextLineHeightWithSpacing() * rows})) {
      for (std::size_t i = mapping_->loops.size(); i-- > 0;) {  // newest first
        const LoopEvent& e = mapping_->loops[i];
        char text[128];
        std::snprintf(text, sizeof text, "frame %d  K%d -> K%d  %s  %.1f ms##loop%zu", e.position, e.loop.from, e.loop.to,
                      metres(e.loop.correction_m).c_str(), e.loop.pose_graph_ms, i);
        if (ImGui::Selectable(text, ui().selected_keyframe == e.loop.to)) bench_.selectKeyframe(e.loop.to);
      }
      ImGui::EndListBox();
    }
    tip("Loop closures, newest first: the frame that closed it, the keyframe it was tracked in -> the keyframe it "
        "revisited, the largest keyframe move of the optimisation and its time. Click to select the revisited keyframe.");
  }

  void drawKeyframes() {
    if (mapping_->keyframes.empty()) return ImGui::TextUnformatted("no keyframes yet");
    if (ImGui::BeginListBox("##keyframes", {-FLT_MIN, ImGui::GetTextLineHeightWithSpacing() * 6.5f})) {
      for (const KeyframeInfo& k : mapping_->keyframes) {
        char text[96];
        std::snprintf(text, sizeof text, "   K%d  frame %d  %zu cells%s", k.id, k.frame, k.ellipsoids,
                      k.id == mapping_->current_keyframe ? "  (current)" : "");
        const ImVec2 at = ImGui::GetCursorScreenPos();
        if (ImGui::Selectable(text, k.id == ui().selected_keyframe)) bench_.selectKeyframe(k.id);
        const float h = ImGui::GetTextLineHeight();
        ImGui::GetWindowDrawList()->AddRectFilled({at.x + 2, at.y + 2}, {at.x + h - 2, at.y + h - 2},
                                                  rgbColor(render::keyframeColor(k.id)));
      }
      ImGui::EndListBox();
    }
    tip("Keyframes with the frame that created them and their container cells; the square is the keyframe's colour "
        "(colour mode \"keyframe\"). Click to inspect.");
    const int id = ui().selected_keyframe;
    if (id < 0 || id >= static_cast<int>(mapping_->keyframes.size())) return ImGui::TextWrapped("Select a keyframe to inspect it.");
    const KeyframeInfo& k = mapping_->keyframes[static_cast<std::size_t>(id)];
    std::size_t kept = 0;
    if (global_ && id < static_cast<int>(global_->map.kept.size())) {
      const std::vector<bool>& cells = global_->map.kept[static_cast<std::size_t>(id)];
      kept = static_cast<std::size_t>(std::count(cells.begin(), cells.end(), true));
    }
    ImGui::TextWrapped("K%d: %zu ellipsoids, %zu kept by the filter, %d frames integrated", id, k.ellipsoids, kept,
                       k.frames_integrated);
    tip("Its local map: one ellipsoid per touched container cell (SPEC 2); of those, the ones the filter keeps with "
        "the live thresholds (min points, k; SPEC 4); and the frames whose depth went into it.");
    const render::Texture2D& container = mirror_.containerTexture();
    if (!mirror_.containerImage().empty()) {
      const float w = ImGui::GetContentRegionAvail().x;
      ImGui::Image(textureId(container), {w, w * container.height() / std::max(1, container.width())});
      tip("The container view (paper Fig. 1): the keyframe's image in the middle of its 2W x 2H container with its "
          "kept ellipsoids projected as 2-sigma ellipses. Click to enlarge.");
      if (ImGui::IsItemClicked()) ui().show_container = true;
    }
    std::string neighbours;
    for (const CovisibilityEdge& e : mapping_->edges)
      if (e.a == id || e.b == id) {
        char item[32];
        std::snprintf(item, sizeof item, "K%d (%.2f) ", e.a == id ? e.b : e.a, e.weight);
        neighbours += item;
      }
    ImGui::TextWrapped("neighbours (edge weight): %s", neighbours.empty() ? "none" : neighbours.c_str());
    tip("Covisibility edges: the share of features one keyframe re-observes of the other (SPEC 5).");
    if (ImGui::Button("View from keyframe")) ui().view_from_keyframe = id;
    tip("Looks through the keyframe with its own intrinsics (its image's aspect kept; Esc or a drag leaves).");
    ImGui::SameLine();
    if (ImGui::Button("Container view")) ui().show_container = true;
    tip("A larger container view with zoom, cell grid and image bounds.");
    checkFits();
    ImGui::TextUnformatted("pose T_W_K (drag to correct):");
    bool moved = false;
    const bool before = ui().show_before_optimisation;
    ImGui::BeginDisabled(before);
    if (beginRows("pose")) {
      label("t (m)", "The keyframe's position in the world, metres. Dragging moves its whole local map; the global map is rebuilt.");
      moved |= ImGui::DragFloat3("##t", &ui().pose_translation_m.x, 0.005f, -1000.f, 1000.f, "%.3f");
      poseEditStarted();
      label("roll, pitch, yaw (deg)", "R = Rz(yaw) Ry(pitch) Rx(roll); pitch stays within +-90 degrees.");
      glm::vec3& rpy = ui().pose_rotation_deg;
      moved |= ImGui::DragFloat3("##rpy", &rpy.x, 0.2f, 0.f, 0.f, "%.1f");
      poseEditStarted();
      ImGui::EndTable();
      // Roll and yaw wrap around; pitch stops at +-90 (beyond it the same rotation has other angles).
      for (float* a : {&rpy.x, &rpy.z}) *a = *a - 360.f * std::round(*a / 360.f);
      rpy.y = std::clamp(rpy.y, -90.f, 90.f);
    }
    ImGui::EndDisabled();
    if (before) tip("Showing the map before the last optimisation: poses are edited on the map after it (B).");
    if (moved) bench_.applyPoseEdit();
    ImGui::BeginDisabled(!bench_.canUndoPoseEdit());
    if (ImGui::Button("Undo pose edit (Ctrl+Z)")) bench_.undoPoseEdit();
    tip(bench_.canUndoPoseEdit() ? "Puts back the pose from before the last drag." : "No pose edit to undo.");
    ImGui::EndDisabled();
  }

  void poseEditStarted() {
    if (ImGui::IsItemActivated()) bench_.beginPoseEdit();
  }

  void drawPicked() {
    if (!ui().picked) return ImGui::TextWrapped("Click an ellipsoid in the view (it is marked magenta).");
    const Ellipsoid& e = *ui().picked;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(e.cov);
    const Eigen::Vector3d axes = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt() * 1000.0;
    if (beginRows("picked")) {
      label("keyframe", "The keyframe it came from (for a merged one, its merge group's centre).");
      ImGui::Text("K%d", e.keyframe);
      label("points n", "Depth points merged into it.");
      ImGui::Text("%u", e.count);
      label("mean (m)", "Its centre in the world frame.");
      ImGui::Text("%.3f, %.3f, %.3f", e.mean.x(), e.mean.y(), e.mean.z());
      label("sigma axes (mm)", "Standard deviations along its principal axes, largest last.");
      ImGui::Text("%.1f, %.1f, %.1f", axes.x(), axes.y(), axes.z());
      label("colour", "Mean RGB of its points.");
      ImGui::ColorButton("##colour", {e.color.x() / 255.f, e.color.y() / 255.f, e.color.z() / 255.f, 1.f});
      ImGui::SameLine();
      ImGui::Text("%.0f, %.0f, %.0f", e.color.x(), e.color.y(), e.color.z());
      ImGui::EndTable();
    }
  }

  void drawPoseFile() {
    ImGui::SetNextItemWidth(-FLT_MIN);
    ImGui::InputTextWithHint("##trajectory", "corrected TUM trajectory file", &ui().trajectory_text);
    tip("A TUM trajectory (timestamp tx ty tz qx qy qz qw): keyframes whose timestamps it names take its poses.");
    ImGui::BeginDisabled(ui().trajectory_text.empty());
    if (ImGui::Button("Load corrected trajectory")) bench_.loadTrajectory();
    tip(ui().trajectory_text.empty() ? "Type the trajectory file's path above first." : "Replaces the matching keyframes' poses; the map is rebuilt.");
    ImGui::EndDisabled();
  }

  void drawExport() {
    if (beginRows("export")) {
      label("folder", "Export writes what `vdmap map --out` writes into this folder (created if missing).");
      ImGui::InputText("##export", &ui().export_text);
      label("session", "Save session writes one .vdmap file with keyframes, local maps and graph (vdmap gui FILE opens it).");
      ImGui::InputText("##session", &ui().session_text);
      ImGui::EndTable();
    }
    ImGui::BeginDisabled(ui().export_text.empty());
    if (ImGui::Button("Export")) bench_.exportMap();
    tip(ui().export_text.empty() ? "Type a folder above first." : "Writes the global map, local maps, poses and graph.");
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::BeginDisabled(ui().session_text.empty());
    if (ImGui::Button("Save session")) bench_.saveSession();
    tip(ui().session_text.empty() ? "Type a file name above first." : "Writes the whole session to one .vdmap file.");
    ImGui::EndDisabled();
    checkFits();
  }

  // --- status bar, overlays, container window, help ----------------------------------------------

  void drawStatusBar() {
    ImGui::SetNextWindowPos({status_.x, status_.y}, ImGuiCond_Always);
    ImGui::SetNextWindowSize({status_.w, status_.h}, ImGuiCond_Always);
    ImGui::Begin("##status", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                     ImGuiWindowFlags_NoBringToFrontOnFocus);
    char right[160];
    const std::size_t shown = global_ ? global_->map.ellipsoids.size() : 0;
    std::snprintf(right, sizeof right, "%zu ellipsoids | frame %.0f ms | H: help", shown, median({frame_times_.begin(), frame_times_.end()}));
    const float right_w = ImGui::CalcTextSize(right).x;
    const StatusLine& st = ui().status;
    ImGui::AlignTextToFramePadding();
    if (!st.text.empty()) {
      ImGui::PushStyleColor(ImGuiCol_Text, kKindColor[static_cast<int>(st.kind)]);
      const float avail = ImGui::GetContentRegionAvail().x - right_w - 3 * ImGui::GetFontSize();
      ImGui::PushClipRect(ImGui::GetCursorScreenPos(), {ImGui::GetCursorScreenPos().x + avail, status_.y + status_.h}, true);
      ImGui::TextUnformatted(st.text.c_str());
      ImGui::PopClipRect();
      ImGui::PopStyleColor();
      tip(st.text);  // the whole message, wrapped, when it is longer than the bar
      ImGui::SameLine(std::max(0.f, avail) + ImGui::GetStyle().WindowPadding.x);
      if (ImGui::SmallButton("x")) ui().status = {StatusLine::Kind::kInfo, "", st.serial + 1};
      tip("Clear the message.");
    }
    ImGui::SameLine(status_.w - right_w - ImGui::GetStyle().WindowPadding.x);
    ImGui::TextUnformatted(right);
    tip("Ellipsoids in the global map shown; the median time of the last 30 UI frames (the window draws only when "
        "something changes, so an idle window costs nothing).");
    ImGui::End();
  }

  // Legends and hints over the 3-D view (drawn in front of it, behind the panels).
  void drawViewOverlay() {
    ImDrawList* draw = ImGui::GetBackgroundDrawList();
    const float font = ImGui::GetFontSize(), pad = 0.6f * font;
    const ImU32 text_color = IM_COL32(230, 230, 230, 255), dim = IM_COL32(170, 170, 170, 255);
    if (preparing_.valid()) {
      const auto [done, total] = std::pair<std::size_t, std::size_t>(progress_->first, progress_->second);
      const float w = std::min(view_.w * 0.6f, 30.f * font), x = view_.x + (view_.w - w) / 2, y = view_.y + view_.h / 2;
      const float share = total > 0 ? static_cast<float>(done) / static_cast<float>(total) : 0.f;
      char text[128];
      std::snprintf(text, sizeof text, "%s: %zu / %zu frames (first start only)", prepare_what_.c_str(), done, total);
      draw->AddText({x, y - 1.6f * font}, text_color, text);
      draw->AddRectFilled({x, y}, {x + w * share, y + font}, IM_COL32(90, 160, 230, 255));
      draw->AddRect({x, y}, {x + w, y + font}, dim);
      return;
    }
    if (!bench_.isOpen()) {
      draw->AddText({view_.x + pad, view_.y + pad}, dim, "Open a TUM RGB-D folder or a .vdmap session (left panel).");
      return;
    }
    const char* mode = ui().view_from_keyframe >= 0 ? "view from keyframe (Esc leaves)"
                       : ui().follow_map            ? "following the map (a drag stops it, F resumes)"
                                                    : "F: frame the map, R: reset, H: help";
    draw->AddText({view_.x + pad, view_.y + pad}, dim, mode);
    float line_y = view_.y + pad + 1.3f * font;
    if (ui().view_from_keyframe >= 0) {
      char text[64];
      std::snprintf(text, sizeof text, "K%d, its own intrinsics", ui().view_from_keyframe);
      draw->AddText({view_.x + pad, line_y}, dim, text);
      line_y += 1.3f * font;
    }
    if (mapping_->mapper.poses == PoseSource::kTrack && ui().view_from_keyframe < 0) {
      // The line colours of tracking, under the mode line.
      float x = view_.x + pad;
      const auto key = [&](const glm::u8vec3& color, const char* text) {
        draw->AddLine({x, line_y + 0.55f * font}, {x + 1.4f * font, line_y + 0.55f * font}, rgbColor(color), 3.f);
        x += 1.8f * font;
        draw->AddText({x, line_y}, text_color, text);
        x += ImGui::CalcTextSize(text).x + font;
      };
      key(render::kTrajectoryColor, "tracked");
      if (mapping_->hasGroundTruth() && ui().settings.show_groundtruth) key(render::kGroundTruthColor, "ground truth");
      if (!mapping_->loops.empty()) key(render::kLoopEdgeColor, "loop closure");
      line_y += 1.3f * font;
    }
    if (ui().show_before_optimisation && !mapping_->loops.empty()) {
      const LoopEvent& last = mapping_->loops.back();
      char text[160];
      std::snprintf(text, sizeof text, "BEFORE the last pose-graph optimisation (loop at frame %d, correction %s; B: after)",
                    last.position, metres(last.loop.correction_m).c_str());
      draw->AddText(ImGui::GetFont(), font, {view_.x + pad, line_y}, rgbColor(render::kLoopEdgeColor), text, nullptr,
                    view_.w - 2 * pad);  // wrapped in a narrow view
    }
    // The colour legend, bottom left.
    const float bar_w = std::min(16.f * font, view_.w - 2 * pad), bar_h = 0.8f * font;
    float y = view_.y + view_.h - pad - bar_h - 1.4f * font;
    const render::ColorMode color = ui().settings.color;
    if (const auto range = mirror_.mapColorRange()) {
      const bool uncertainty = color == render::ColorMode::kUncertainty;
      draw->AddText({view_.x + pad, y - 1.4f * font}, text_color,
                    uncertainty ? "largest std. deviation (log scale)" : "points per ellipsoid (log scale)");
      drawRamp(draw, {view_.x + pad, y}, bar_w, bar_h);
      char lo[32], hi[32];
      if (uncertainty) {
        std::snprintf(lo, sizeof lo, "%s", metres(range->lo).c_str());
        std::snprintf(hi, sizeof hi, "%s", metres(range->hi).c_str());
      } else {
        std::snprintf(lo, sizeof lo, "%.0f", range->lo);
        std::snprintf(hi, sizeof hi, "%.0f", range->hi);
      }
      draw->AddText({view_.x + pad, y + bar_h + 2}, text_color, lo);
      draw->AddText({view_.x + pad + bar_w - ImGui::CalcTextSize(hi).x, y + bar_h + 2}, text_color, hi);
    } else if (color == render::ColorMode::kKeyframe && !mapping_->keyframes.empty()) {
      // A swatch per keyframe, as many as fit in two rows.
      const float cell = 3.2f * font;
      const int per_row = std::max(1, static_cast<int>((view_.w - 2 * pad) / cell));
      const int n = static_cast<int>(mapping_->keyframes.size()), rows = std::min(2, (n + per_row - 1) / per_row);
      float top = view_.y + view_.h - pad - rows * 1.3f * font;
      draw->AddText({view_.x + pad, top - 1.4f * font}, text_color, "keyframe colours");
      for (int i = 0; i < std::min(n, 2 * per_row); ++i) {
        const float x = view_.x + pad + (i % per_row) * cell, yy = top + (i / per_row) * 1.3f * font;
        draw->AddRectFilled({x, yy + 2}, {x + 0.9f * font, yy + font}, rgbColor(render::keyframeColor(i)));
        char text[16];
        std::snprintf(text, sizeof text, i + 1 == 2 * per_row && n > 2 * per_row ? "K%d.." : "K%d", i);
        draw->AddText({x + 1.1f * font, yy}, text_color, text);
      }
    }
    // The up axis, bottom right.
    const glm::vec3 up = ui().camera.up;
    char text[96];
    std::snprintf(text, sizeof text, "up: %s (%.2f, %.2f, %.2f)", kUpAxisNames[static_cast<int>(ui().settings.up_axis)], up.x,
                  up.y, up.z);
    const ImVec2 size = ImGui::CalcTextSize(text);
    draw->AddText({view_.x + view_.w - pad - size.x, view_.y + view_.h - pad - size.y}, dim, text);
  }

  void drawContainerWindow() {
    if (!ui().show_container || mirror_.containerImage().empty() || !mapping_) return;
    const ImVec2 display = ImGui::GetIO().DisplaySize;
    ImGui::SetNextWindowSize({display.x * 0.55f, display.y * 0.6f}, ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowPos({display.x * 0.22f, display.y * 0.15f}, ImGuiCond_FirstUseEver);
    char title[64];
    std::snprintf(title, sizeof title, "Container view K%d###container", ui().selected_keyframe);
    if (!ImGui::Begin(title, &ui().show_container)) return ImGui::End();
    Settings& s = ui().settings;
    ImGui::Checkbox("cell grid", &s.container_grid);
    tip("The container's cells (s px of the keyframe image), drawn once they are 4 screen pixels apart.");
    ImGui::SameLine();
    ImGui::Checkbox("image bounds", &s.container_bounds);
    tip("The keyframe's own W x H image inside the 2W x 2H container.");
    ImGui::SameLine();
    ImGui::SetNextItemWidth(8.f * ImGui::GetFontSize());
    ImGui::SliderFloat("zoom", &container_zoom_, 1.f, 16.f, "%.1fx", ImGuiSliderFlags_Logarithmic);
    ImGui::SameLine();
    if (ImGui::Button("fit")) container_zoom_ = 1.f, container_center_ = {0.5f, 0.5f};
    const render::Texture2D& t = mirror_.containerTexture();
    const ImVec2 avail = ImGui::GetContentRegionAvail();
    const float aspect = static_cast<float>(t.width()) / std::max(1, t.height());
    const ImVec2 size = avail.x / aspect <= avail.y ? ImVec2(avail.x, avail.x / aspect) : ImVec2(avail.y * aspect, avail.y);
    const ImVec2 at = ImGui::GetCursorScreenPos();
    // The visible part of the container, in texture coordinates.
    const float half = 0.5f / container_zoom_;
    container_center_.x = std::clamp(container_center_.x, half, 1.f - half);
    container_center_.y = std::clamp(container_center_.y, half, 1.f - half);
    const ImVec2 uv0(container_center_.x - half, container_center_.y - half), uv1(container_center_.x + half, container_center_.y + half);
    ImGui::Image(textureId(t), size, uv0, uv1);
    const bool hovered = ImGui::IsItemHovered();
    if (hovered && ImGui::GetIO().MouseWheel != 0.f) {
      // Zoom about the pixel under the cursor.
      const ImVec2 m = ImGui::GetIO().MousePos;
      const ImVec2 uv(uv0.x + (m.x - at.x) / size.x * (uv1.x - uv0.x), uv0.y + (m.y - at.y) / size.y * (uv1.y - uv0.y));
      const float old_zoom = container_zoom_;
      container_zoom_ = std::clamp(container_zoom_ * std::pow(1.25f, ImGui::GetIO().MouseWheel), 1.f, 16.f);
      const float k = old_zoom / container_zoom_;
      container_center_ = {uv.x + (container_center_.x - uv.x) * k, uv.y + (container_center_.y - uv.y) * k};
    }
    if (hovered && ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
      const ImVec2 d = ImGui::GetIO().MouseDelta;
      container_center_.x -= d.x / size.x / container_zoom_;
      container_center_.y -= d.y / size.y / container_zoom_;
    }
    // Overlays in container pixels -> screen.
    const float cw = static_cast<float>(t.width()), ch = static_cast<float>(t.height());
    const auto screen = [&](float u, float v) {
      return ImVec2(at.x + (u / cw - uv0.x) / (uv1.x - uv0.x) * size.x, at.y + (v / ch - uv0.y) / (uv1.y - uv0.y) * size.y);
    };
    ImDrawList* draw = ImGui::GetWindowDrawList();
    draw->PushClipRect(at, {at.x + size.x, at.y + size.y}, true);
    const int cell = mapping_->mapper.local_map.cell_size_px;
    const float px = size.x / (cw * (uv1.x - uv0.x));  // screen pixels per container pixel
    if (s.container_grid && cell * px >= 4.f) {
      const int c0 = static_cast<int>(uv0.x * cw / cell), c1 = static_cast<int>(uv1.x * cw / cell) + 1;
      const int r0 = static_cast<int>(uv0.y * ch / cell), r1 = static_cast<int>(uv1.y * ch / cell) + 1;
      for (int c = c0; c <= c1; ++c) draw->AddLine(screen(c * cell, 0), screen(c * cell, ch), IM_COL32(255, 255, 255, 50));
      for (int r = r0; r <= r1; ++r) draw->AddLine(screen(0, r * cell), screen(cw, r * cell), IM_COL32(255, 255, 255, 50));
    }
    if (s.container_bounds)
      draw->AddRect(screen(cw / 4, ch / 4), screen(cw * 3 / 4, ch * 3 / 4), IM_COL32(255, 220, 0, 200), 0.f, 0, 1.5f);
    draw->PopClipRect();
    ImGui::End();
  }

  void drawHelp() {
    help_ = {};
    if (!ui().show_help) return;
    // Over the 3-D view, as wide as it (wrapping the descriptions) but at least 40 characters.
    const ImVec2 display = ImGui::GetIO().DisplaySize;
    const float font = ImGui::GetFontSize();
    const float width = std::min(display.x * 0.95f, std::max(view_.w - 2.f * font, 40.f * font));
    ImGui::SetNextWindowPos({view_.x + view_.w / 2, view_.y + view_.h / 2}, ImGuiCond_Always, {0.5f, 0.5f});
    ImGui::SetNextWindowSize({width, 0.f}, ImGuiCond_Always);  // 0: the height fits the content
    ImGui::Begin("Keys and mouse (H, F1 or Esc closes)", &ui().show_help,
                 ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoResize);
    if (ImGui::BeginTable("keys", 2, ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("keys", ImGuiTableColumnFlags_WidthFixed);
      ImGui::TableSetupColumn("what", ImGuiTableColumnFlags_WidthStretch);
      for (const auto& [keys, what] : keyHelp()) {
        ImGui::TableNextRow();
        ImGui::TableSetColumnIndex(0);
        ImGui::TextColored({1.f, 0.86f, 0.4f, 1.f}, "%s", keys);
        ImGui::TableSetColumnIndex(1);
        ImGui::TextWrapped("%s", what);
      }
      ImGui::EndTable();
    }
    ImGui::TextDisabled("Hover over any control or figure for what it means.");
    help_ = {ImGui::GetWindowPos().x, ImGui::GetWindowPos().y, ImGui::GetWindowWidth(), ImGui::GetWindowHeight()};
    ImGui::End();
  }

  // --- the scripted path --------------------------------------------------------------------------

  // Once mapping and map building are done: reset the view, draw a few frames, take the
  // screenshot, then the measurements asked for, then the figures.
  enum class Phase { kWaitDone, kSettle, kLatency, kOrbit, kIdle, kFinish, kDone };

  void advanceScript() {
    if (!scripted() || script_phase_ == Phase::kDone || preparing_.valid()) return;
    switch (script_phase_) {
      case Phase::kWaitDone: {
        if (bench_.isOpen()) {
          const PlayerStatus st = bench_.player();
          const bool done = !st.busy && (st.target >= mapping_->frames_total || !script_.play_to_end || !st.error.empty());
          if (!done) return;
        }
        bench_.resetView();
        if (script_.keyframe >= 0) bench_.selectKeyframe(script_.keyframe);
        for (const int key : script_.press) keys_.presses.emplace_back(key, 0);  // as if typed now
        countdown_ = 3;  // frames to draw the final map before the screenshot
        script_phase_ = Phase::kSettle;
        return;
      }
      case Phase::kSettle:
        if (bench_.player().busy) return;  // a key pressed above may have asked for a rebuild
        if (--countdown_ > 0) return;
        recordLayout();
        if (!script_.screenshot.empty() && !failedRun()) {
          saveScreenshot(script_.screenshot);
          screenshot_taken_ = true;
        }
        script_phase_ = Phase::kLatency;
        return;
      case Phase::kLatency:
        if (measureLatency()) return;
        script_phase_ = Phase::kOrbit;
        return;
      case Phase::kOrbit:
        if (static_cast<int>(orbit_ms_.size()) < script_.orbit_frames) {
          const double cpu = processCpuSeconds();
          if (orbit_started_) {
            orbit_ms_.push_back(msSince(orbit_frame_start_));
            orbit_cpu_ms_.push_back(1e3 * (cpu - orbit_cpu_start_));
          }
          orbit_started_ = true;
          bench_.orbit(0.03f, 0.f);
          orbit_frame_start_ = Clock::now();
          orbit_cpu_start_ = cpu;
          return;
        }
        if (bench_.player().busy || settle_frames_ > 0) return;  // idle: the worker and the UI
        script_phase_ = Phase::kIdle;  // starts once this frame is on screen (frame())
        idle_until_ = Clock::time_point::max();
        return;
      case Phase::kIdle:
        if (Clock::now() < idle_until_) return;
        script_phase_ = Phase::kFinish;
        return;
      case Phase::kFinish:
        // A failed scripted run (--exit with an error, e.g. a bad session) writes neither file:
        // a screenshot of the error would pass for a result (issue #17). One taken before a
        // later failure is removed.
        if (!failedRun() && !script_.stats_json.empty()) writeStats(script_.stats_json);
        if (failedRun() && screenshot_taken_) {
          std::error_code ignored;
          std::filesystem::remove(script_.screenshot, ignored);
        }
        script_finished_ = script_.exit;
        script_phase_ = Phase::kDone;
        return;
      case Phase::kDone: return;
    }
  }

  // One slider change at a time (merge distance, alternating): from the edit until the frame
  // that shows the map built with it. Returns true while runs remain.
  bool measureLatency() {
    if (!bench_.isOpen() || !global_) return false;
    if (latency_generation_ >= 0) {
      if (global_->generation <= latency_generation_ || bench_.player().busy) return true;
      latency_ms_.push_back(msSince(latency_start_));  // this frame draws the new map
      latency_generation_ = -1;
    }
    if (static_cast<int>(latency_ms_.size()) >= script_.latency_runs) return false;
    const Parameter& p = *findParameter("merge_distance");
    latency_generation_ = global_->generation;
    latency_start_ = Clock::now();
    bench_.editParameter(p, latency_ms_.size() % 2 == 0 ? 0.2 : GlobalMapParams{}.merge_distance_m);
    return true;
  }

  // Where the panels and the 3-D view are and where the map projects, for the stats file.
  void recordLayout() {
    layout_ = {{"window", {fb_width_, fb_height_}},
               {"viewport", view_.json()},
               {"panels", {{"Sequence", left_.json()}, {"Map", right_.json()}, {"Status", status_.json()}}},
               {"labels_cut", labels_cut_},
               {"help", help_.json()},  // all zero while the help is closed
               {"up", {ui().camera.up.x, ui().camera.up.y, ui().camera.up.z}}};
    if (!global_ || global_->map.ellipsoids.empty()) return;
    std::vector<glm::vec3> means;
    for (const Ellipsoid& e : global_->map.ellipsoids) means.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
    const auto [lo, hi] = render::robustBounds(means);
    const ViewportView v = bench_.view(ui().view_width, ui().view_height);
    float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 p((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
      const glm::vec4 q = v.camera.T_C_W * glm::vec4(p, 1.f);
      const float u = v.camera.fx * q.x / q.z + v.camera.cx + view_.x + v.image.x;
      const float w = v.camera.fy * q.y / q.z + v.camera.cy + view_.y + v.image.y;
      x0 = std::min(x0, u), y0 = std::min(y0, w), x1 = std::max(x1, u), y1 = std::max(y1, w);
    }
    layout_["map_bbox_px"] = {x0, y0, x1, y1};
  }

  void saveScreenshot(const std::string& file) {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl_.ReadBuffer(GL_BACK);
    const cv::Mat image = render::readFramebufferRgb(gl_, 0, 0, fb_width_, fb_height_);
    std::error_code ignored;
    const std::string path = std::filesystem::absolute(file, ignored).lexically_normal().string();
    try {
      render::writePng(path, image);
      bench_.report(StatusLine::Kind::kSuccess, "screenshot written to " + path);
    } catch (const std::exception& e) {
      bench_.report(StatusLine::Kind::kError, e.what());
    }
  }

  void writeStats(const std::string& file) {
    nlohmann::json stats = {{"error", bench_.firstError()}};
    if (mapping_) {
      stats["frames_mapped"] = mapping_->frames_mapped;
      stats["frames_total"] = mapping_->frames_total;
      stats["keyframes"] = mapping_->keyframes.size();
      stats["edges"] = mapping_->edges.size();
      stats["cell_size_px"] = mapping_->mapper.local_map.cell_size_px;
      stats["loop_closures"] = mapping_->loops.size();
      stats["frames_lost"] = mapping_->frames_lost;
      stats["frames_weak"] = mapping_->frames_weak;
      stats["frames_relocalised"] = mapping_->frames_relocalised;
      stats["has_groundtruth"] = mapping_->hasGroundTruth();
    }
    if (global_) {
      stats["sigma_e"] = global_->map.sigma_e;
      stats["merged"] = global_->map.merged;
      stats["sigma_e_prime"] = global_->map.sigma_e_prime;
      stats["t_g_s"] = global_->map.t_g_s;
      stats["merge_distance_m"] = global_->params.merge_distance_m;
    }
    stats["ui_frames_while_busy"] = busy_frame_ms_.size();
    stats["ui_frame_ms_median_while_busy"] = median(busy_frame_ms_);
    stats["layout"] = layout_;
    stats["show_help"] = ui().show_help;
    stats["view_from_keyframe"] = ui().view_from_keyframe;
    stats["show_before_optimisation"] = ui().show_before_optimisation;
    if (global_) stats["map_before_optimisation"] = global_->before_optimisation;
    if (!latency_ms_.empty()) stats["slider_to_map_ms"] = latency_ms_;
    if (!orbit_ms_.empty()) {
      stats["orbit_frame_ms"] = orbit_ms_;
      stats["orbit_frame_cpu_ms"] = orbit_cpu_ms_;  // process CPU (all of llvmpipe's threads), per frame
    }
    if (script_.idle_seconds > 0) {
      stats["idle_cpu_s"] = idle_cpu_s_;
      stats["idle_frames"] = idle_frames_;  // UI frames drawn meanwhile
    }
    try {
      writeFileAtomically(file, jsonText(stats) + "\n");
    } catch (const std::exception& e) {
      bench_.report(StatusLine::Kind::kError, e.what());
    }
  }

  Workbench& bench_;
  GlfwWindowContext& context_;
  const render::Gl& gl_;
  ScriptOptions script_;
  bool screenshot_taken_ = false;  // by the script, so a failure removes it (and no older file)
  KeyQueue& keys_;
  render::MapMirror mirror_;
  std::shared_ptr<const MappingSnapshot> mapping_;
  std::shared_ptr<const GlobalSnapshot> global_;
  int mirrored_session_ = 0;
  int session_base_ = 0;
  int decoded_rgb_for_ = -1;  // the container generation decoded_rgb_ was decoded for
  cv::Mat decoded_rgb_;
  Seen last_seen_;
  int settle_frames_ = 2;
  // Preparation (the built-in scene) on its own thread.
  std::future<std::string> preparing_;
  std::string prepare_what_;
  SequenceArgs prepare_args_;
  std::shared_ptr<std::pair<std::atomic<std::size_t>, std::atomic<std::size_t>>> progress_ =
      std::make_shared<std::pair<std::atomic<std::size_t>, std::atomic<std::size_t>>>(0, 0);
  // Layout (ImGui coordinates).
  Rect left_, right_, status_, view_, help_;
  float left_w_ = 0, right_w_ = 0, status_h_ = 0;
  ImVec2 last_size_{0, 0};
  int fb_width_ = 0, fb_height_ = 0;
  int labels_cut_ = 0;
  float below_images_px_ = 0;  ///< the left panel's depth scale and stage times, as last drawn
  bool drag_in_view_[3] = {false, false, false};
  int scrub_ = 0;
  bool scrubbing_ = false;
  float container_zoom_ = 1.f;
  ImVec2 container_center_{0.5f, 0.5f};
  std::string screenshot_text_ = "vdmap_screenshot.png", screenshot_request_;
  double frame_ms_ = 0;
  std::deque<double> frame_times_;
  std::vector<double> busy_frame_ms_;
  // Script.
  Phase script_phase_ = Phase::kWaitDone;
  int countdown_ = 0;
  bool script_finished_ = false;
  nlohmann::json layout_ = nlohmann::json::object();
  int latency_generation_ = -1;
  Clock::time_point latency_start_, orbit_frame_start_, idle_until_;
  std::vector<double> latency_ms_, orbit_ms_, orbit_cpu_ms_;
  double orbit_cpu_start_ = 0;
  bool orbit_started_ = false;
  double idle_cpu_start_ = 0, idle_cpu_s_ = 0;
  int idle_frames_ = 0;
};

}  // namespace

std::vector<int> parseKeyNames(const std::string& comma_separated) {
  std::vector<int> keys;
  std::stringstream in(comma_separated);
  for (std::string name; std::getline(in, name, ',');) {
    if (name.size() == 1 && name[0] >= 'a' && name[0] <= 'z') keys.push_back(GLFW_KEY_A + (name[0] - 'a'));
    else if (name == "space") keys.push_back(GLFW_KEY_SPACE);
    else if (name == "right") keys.push_back(GLFW_KEY_RIGHT);
    else if (name == "left") keys.push_back(GLFW_KEY_LEFT);
    else if (name == "f1") keys.push_back(GLFW_KEY_F1);
    else if (name == "esc") keys.push_back(GLFW_KEY_ESCAPE);
    else throw std::invalid_argument("--press: unknown key '" + name + "' (a-z, space, right, left, f1, esc)");
  }
  return keys;
}

int runWorkbenchWindow(Workbench& bench, const ScriptOptions& script, const std::string& settings_file, Preparation prepare) {
  Settings& s = bench.ui().settings;
  GlfwWindowContext context(s.window_width, s.window_height, "vdmap workbench");
  KeyQueue keys;
  glfwSetWindowUserPointer(context.window(), &keys);
  installInputCallbacks(context.window());
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  const std::string ini = settings_file.empty() ? "" : (std::filesystem::path(settings_file).parent_path() / "imgui.ini").string();
  ImGui::GetIO().IniFilename = ini.empty() ? nullptr : ini.c_str();
  ImGui::GetIO().ConfigInputTextCursorBlink = false;  // a blinking cursor would need frames while idle
  std::error_code ignored;  // ImGui writes imgui.ini at DestroyContext, before the settings make the folder
  if (!ini.empty()) std::filesystem::create_directories(std::filesystem::path(ini).parent_path(), ignored);
  ImGui::StyleColorsDark();
  // HiDPI screens: scale fonts and sizes by the window's content scale (1 on a plain X server).
  float scale_x = 1.f, scale_y = 1.f;
  glfwGetWindowContentScale(context.window(), &scale_x, &scale_y);
  if (scale_y > 1.f) {
    ImFontConfig font;
    font.SizePixels = 13.f * scale_y;
    ImGui::GetIO().Fonts->AddFontDefault(&font);
    ImGui::GetStyle().ScaleAllSizes(scale_y);
  }
  if (!ImGui_ImplGlfw_InitForOpenGL(context.window(), true) || !ImGui_ImplOpenGL3_Init("#version 330"))
    throw std::runtime_error("Dear ImGui could not initialise its OpenGL 3 backend");
  int code = 0;
  {
    WorkbenchWindow window(bench, context, script, std::move(prepare), keys);
    while (window.step()) {
    }
    code = window.exitCode();
  }
  glfwGetWindowSize(context.window(), &s.window_width, &s.window_height);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  return code;
}

}  // namespace vdmap::app::gui
