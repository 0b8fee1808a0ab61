// The workbench window: the GLFW window and Dear ImGui's lifecycle, the event loop that draws a
// frame only when something may have changed, the layout of the panels around the 3-D view, the
// keys, and the preparation thread. What a frame draws is in the panel, view and script files.
#include "app/window/workbench_window.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "app/cli/error_text.h"
#include "app/window/container_window.h"
#include "app/window/glfw_context.h"
#include "app/window/map_panel.h"
#include "app/window/measure_overlay.h"
#include "app/window/scene_view.h"
#include "app/window/script_driver.h"
#include "app/window/sequence_panel.h"
#include "app/window/widgets.h"
#include "app/window/window_state.h"
#include "mapping/core/timing.h"
#include "render/view_cache.h"

namespace vdmap::app::gui {
namespace {

using Clock = std::chrono::steady_clock;

KeyQueue& keyQueue(GLFWwindow* window) { return *static_cast<KeyQueue*>(glfwGetWindowUserPointer(window)); }

// Installed before Dear ImGui's, which chains to them.
void installInputCallbacks(GLFWwindow* window) {
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
    ++keyQueue(w).events;
    if (action == GLFW_PRESS || (action == GLFW_REPEAT && (key == GLFW_KEY_LEFT || key == GLFW_KEY_RIGHT)))
      keyQueue(w).presses.emplace_back(key, mods);
  });
  glfwSetCursorPosCallback(window, [](GLFWwindow* w, double, double) { ++keyQueue(w).events; });
  glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int button, int action, int) {
    KeyQueue& q = keyQueue(w);
    ++q.events;
    double x = 0, y = 0;
    glfwGetCursorPos(w, &x, &y);
    if (button == GLFW_MOUSE_BUTTON_LEFT && action == GLFW_PRESS && q.double_click.press(glfwGetTime(), x, y))
      ++q.double_clicks;
  });
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double) { ++keyQueue(w).events; });
  glfwSetCharCallback(window, [](GLFWwindow* w, unsigned) { ++keyQueue(w).events; });
  glfwSetWindowFocusCallback(window, [](GLFWwindow* w, int) { ++keyQueue(w).events; });
  glfwSetCursorEnterCallback(window, [](GLFWwindow* w, int) { ++keyQueue(w).events; });
  glfwSetFramebufferSizeCallback(window, [](GLFWwindow* w, int, int) { ++keyQueue(w).events; });
  glfwSetWindowRefreshCallback(window, [](GLFWwindow* w) { ++keyQueue(w).events; });
  // Opening files: paths dropped on the window wait for the next frame (FileActions::drop).
  glfwSetDropCallback(window, [](GLFWwindow* w, int count, const char** paths) {
    ++keyQueue(w).events;
    for (int i = 0; i < count; ++i) keyQueue(w).dropped.emplace_back(paths[i]);
  });
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
    case GLFW_KEY_S:  // writes a file: never a letter typed by mistake (a text field that lost the keyboard)
      if (mods & GLFW_MOD_CONTROL) return KeyAction::kSaveView;
      return std::nullopt;
    case GLFW_KEY_T: return KeyAction::kFrameTrajectories;
    case GLFW_KEY_P: return KeyAction::kPivotHere;
    case GLFW_KEY_Q: return KeyAction::kProbe;
    case GLFW_KEY_D: return KeyAction::kEditDiff;
    case GLFW_KEY_PAGE_UP: return KeyAction::kSliceUp;
    case GLFW_KEY_PAGE_DOWN: return KeyAction::kSliceDown;
    case GLFW_KEY_H:
    case GLFW_KEY_F1: return KeyAction::kHelp;
    case GLFW_KEY_ESCAPE: return KeyAction::kEscape;
    case GLFW_KEY_Z:
      if (mods & GLFW_MOD_CONTROL) return KeyAction::kUndo;
      return std::nullopt;
    default: return std::nullopt;
  }
}

// The queued key presses as Workbench actions (none while a text field has the keyboard, but F1).
void handleKeys(Workbench& bench, KeyQueue& keys) {
  const bool typing = ImGui::GetIO().WantTextInput;
  while (!keys.presses.empty()) {
    const auto [key, mods] = keys.presses.front();
    keys.presses.pop_front();
    if (typing && key != GLFW_KEY_F1) continue;    // the key belongs to a text field
    if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9) {  // quick views: Ctrl+N keeps the view, N shows it
      bench.noteAction();
      ViewFiles& views = bench.viewFiles();
      (mods & GLFW_MOD_CONTROL) ? views.storeQuickView(key - GLFW_KEY_0)
                                : void(views.recallQuickView(key - GLFW_KEY_0));
      continue;
    }
    if (const auto action = actionOf(key, mods)) bench.key(*action);
  }
}

// Panels docked to the left and right edges, the status bar along the bottom and the 3-D
// viewport between them; widths follow the window (the user may drag a panel's inner edge).
void layOut(Layout& at, UiState& ui) {
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  const float font = ImGui::GetFontSize();
  at.status_h = ImGui::GetFrameHeight() + 2.f * ImGui::GetStyle().WindowPadding.y;
  const float body_h = std::max(1.f, size.y - at.status_h);
  const float default_left = std::clamp(0.25f * size.x, 24.f * font, 42.f * font);
  const float default_right = std::clamp(0.28f * size.x, 27.f * font, 46.f * font);
  if (ui.reset_layout || at.left_w <= 0 || size.x != at.last_size.x) at.left_w = default_left;
  if (ui.reset_layout || at.right_w <= 0 || size.x != at.last_size.x) at.right_w = default_right;
  // Keep at least a third of the width for the 3-D view.
  const float max_panels = size.x * 2.f / 3.f;
  if (at.left_w + at.right_w > max_panels) {
    const float k = max_panels / (at.left_w + at.right_w);
    at.left_w *= k;
    at.right_w *= k;
  }
  at.last_size = size;
  at.left = {0, 0, at.left_w, body_h};
  at.right = {size.x - at.right_w, 0, at.right_w, body_h};
  at.status = {0, body_h, size.x, at.status_h};
  at.view = {at.left_w, 0, std::max(1.f, size.x - at.left_w - at.right_w), body_h};
  const ImVec2 scale = ImGui::GetIO().DisplayFramebufferScale;
  ui.view_width = std::max(1, static_cast<int>(at.view.w * scale.x));
  ui.view_height = std::max(1, static_cast<int>(at.view.h * scale.y));
}

// The preparation (Preparation::run) on its own thread, its progress for the view's overlay.
struct Preparing {
  std::future<std::string> folder;
  std::string what;
  SequenceArgs args;
  std::shared_ptr<std::pair<std::atomic<std::size_t>, std::atomic<std::size_t>>> progress =
      std::make_shared<std::pair<std::atomic<std::size_t>, std::atomic<std::size_t>>>(0, 0);
  std::shared_ptr<std::atomic<bool>> cancel = std::make_shared<std::atomic<bool>>(false);
};

class WorkbenchWindow {
 public:
  WorkbenchWindow(Workbench& bench, GlfwWindowContext& context, const ScriptOptions& script, Preparation prepare,
                  KeyQueue& keys)
      : bench_(bench), context_(context), gl_(context.gl()), keys_(keys), mirror_(gl_), view_cache_(gl_),
        motion_(script.fast_budget) {
    script_.options = script;
    win_.check.expand_sections = script.expand_sections;
    bench_.setOnChange([] { glfwPostEmptyEvent(); });
    if (prepare.run) {
      preparing_.what = prepare.what;
      preparing_.args = prepare.args;
      auto progress = preparing_.progress;
      auto cancel = preparing_.cancel;
      preparing_.folder = std::async(std::launch::async, [run = std::move(prepare.run), progress, cancel] {
        return run(
            [progress](std::size_t done, std::size_t total) {
              progress->first = done;
              progress->second = total;
              glfwPostEmptyEvent();
            },
            [cancel] { return cancel->load(); });
      });
    } else {
      startScript(script_, bench_);
    }
  }

  ~WorkbenchWindow() {
    if (preparing_.folder.valid()) cancelPreparation();
    bench_.setOnChange(nullptr);
  }

  // Waits for input, news from the worker or a deadline, and draws a frame only when something
  // may have changed: an idle window costs (almost) nothing. Returns false when it should close.
  bool step() {
    bench_.autosaveSettings(Clock::now());  // settings: 1 s after the last change
    if (!needsFrame()) {
      glfwWaitEventsTimeout(waitSeconds());
      if (!needsFrame()) return !glfwWindowShouldClose(context_.window()) && !script_.finished;
    }
    glfwPollEvents();
    frame();
    return !glfwWindowShouldClose(context_.window()) && !script_.finished;
  }

  int exitCode() const { return failedRun(script_, bench_) ? 1 : 0; }

 private:
  // What the newest snapshots are, to notice news without drawing.
  struct Seen {
    int session = 0;
    const void *mapping = nullptr, *global = nullptr, *selection = nullptr;
    int status = -1;
    bool busy = false;
    bool operator==(const Seen&) const = default;
  };
  Seen seen() const {
    Seen s;
    s.status = bench_.ui().status.serial;
    if (bench_.isOpen()) {
      s.session = bench_.sessionSerial();
      s.mapping = bench_.mapping().get();
      s.global = bench_.global().get();
      s.selection = bench_.selection().get();
      s.busy = bench_.player().status().busy;
    }
    return s;
  }

  bool needsFrame() const {
    if (keys_.events > 0 || !keys_.presses.empty() || settle_frames_ > 0) return true;
    if (const auto due = motion_.secondsToFullFrame(Clock::now()); due && *due <= 0.0) return true;  // the camera rests
    if (preparing_.folder.valid())  // the progress bar, woken by the renderer's progress (no busy loop beside it)
      return preparing_.progress->first != win_.prepare_done ||
             preparing_.folder.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
    const ScriptPhase phase = script_.phase;
    if (scripted(script_)) {
      if (phase == ScriptPhase::kSettle || phase == ScriptPhase::kOrbit || phase == ScriptPhase::kFinish) return true;
      if (phase == ScriptPhase::kLatency && script_.latency_generation < 0) return true;  // the next edit
      if (phase == ScriptPhase::kIdle) return Clock::now() >= script_.idle_until;
    }
    const Seen now = seen();
    return !(now == last_seen_) || (scripted(script_) && phase == ScriptPhase::kWaitDone && now.busy);
  }

  double waitSeconds() const {
    // After a fast frame the loop wakes itself for the full-quality one.
    if (const auto due = motion_.secondsToFullFrame(Clock::now())) return *due;
    if (script_.phase == ScriptPhase::kIdle)
      return std::max(0.0, std::chrono::duration<double>(script_.idle_until - Clock::now()).count());
    if (preparing_.folder.valid()) return 0.2;
    // The worker wakes the loop itself (Workbench::setOnChange); the timeout is a safety net,
    // and the settings' autosave wakes it when due.
    return std::min(2.0, bench_.autosaveSettings(Clock::now()) + 0.01);
  }

  void frame() {
    const auto t0 = Clock::now();
    if (++frames_drawn_ == script_.options.close_after_frames) glfwSetWindowShouldClose(context_.window(), GLFW_TRUE);
    scriptFrameStarts(script_, t0);
    // ImGui shows hover and active states a frame late: after input, draw two more frames.
    settle_frames_ = keys_.events > 0 ? 2 : std::max(0, settle_frames_ - 1);
    keys_.events = 0;
    win_.double_click = std::exchange(keys_.double_clicks, 0) > 0;
    if (preparing_.folder.valid() && preparing_.folder.wait_for(std::chrono::seconds(0)) == std::future_status::ready)
      finishPreparation();
    showPreparation();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    glfwGetFramebufferSize(context_.window(), &win_.layout.fb_width, &win_.layout.fb_height);
    layOut(win_.layout, bench_.ui());
    // A click anywhere but on the status line (its x, its tooltip) starts a new action: the
    // status line's older message goes (what the action reports replaces it).
    const ImGuiIO& io = ImGui::GetIO();
    if ((io.MouseClicked[0] || io.MouseClicked[1] || io.MouseClicked[2]) && !win_.layout.status.contains(io.MousePos))
      bench_.noteAction();
    handleKeys(bench_, keys_);
    // Opening files: what was dropped (or --drop) opens before this frame reads the model.
    for (std::string& path : keys_.dropped) bench_.files().drop(std::move(path));
    keys_.dropped.clear();
    bench_.files().openDropped();
    bench_.sync();
    win_.mapping = bench_.mapping();
    win_.global = bench_.global();
    // What this frame draws, read before drawing: news that arrives while it draws differs from
    // it, so the loop draws again instead of waiting with a stale picture.
    const Seen drawn = seen();
    syncMirror(bench_, mirror_, win_);
    win_.check.labels_cut = 0;
    drawSequencePanel(bench_, mirror_, win_);
    drawMapPanel(bench_, mirror_, win_);
    drawStatusBar(bench_, win_);
    drawViewOverlay(bench_, win_);
    drawContainerWindow(bench_, mirror_, win_);
    drawHelp(bench_, win_);
    handleMouse(bench_, win_);
    handleViewTools(bench_, win_);  // wheel, double-click, P, Ctrl+click: probes answered below
    drawViewMarks(bench_, win_);
    bench_.ui().reset_layout = false;
    // A new session draws panels and tables it has not drawn before: let them settle.
    if (drawn.session != last_seen_.session) settle_frames_ = std::max(settle_frames_, 2);
    last_seen_ = drawn;
    // Tables still sizing their columns clip their labels in this frame: draw the next one too.
    if (takeTablesSettling() > 0) settle_frames_ = std::max(settle_frames_, 1);
    // The picture a user looks at is the frame after which the loop waits for input: the labels
    // it cuts (a scripted run draws on through its own phases, so the loop's own rule decides).
    if (!preparing_.folder.valid() && keys_.events == 0 && keys_.presses.empty() && settle_frames_ == 0)
      script_.labels_cut_before_wait = std::max(script_.labels_cut_before_wait, win_.check.labels_cut);
    ImGui::Render();
    drawView();
    // The drawn scene's depth under the cursor; a probe whose text changed shows in the next frame.
    if (answerProbes(bench_, gl_, win_)) settle_frames_ = std::max(settle_frames_, 1);
    if (viewScreenshotDue(script_, bench_))
      saveViewScreenshot(bench_, gl_, mirror_, win_, script_.options.view_screenshot);
    if (!win_.screenshot_request.empty() && win_.screenshot_request_view) {  // the 3-D view alone
      saveViewScreenshot(bench_, gl_, mirror_, win_, win_.screenshot_request);
      win_.screenshot_request.clear();
    }
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (!win_.screenshot_request.empty()) {
      saveScreenshot(bench_, gl_, win_, win_.screenshot_request);
      win_.screenshot_request.clear();
    }
    ScriptedWindow scripted_window(bench_, gl_, win_, keys_);
    advanceScript(script_, bench_, scripted_window, {win_.mapping, win_.global, win_.preparing, settle_frames_});
    glfwSwapBuffers(context_.window());
    const double frame_ms = msSince(t0);
    scriptFrameShown(script_, t0);
    win_.frame_times.push_back(frame_ms);
    if (win_.frame_times.size() > 30) win_.frame_times.pop_front();
    if (bench_.player().status().busy) script_.busy_frame_ms.push_back(frame_ms);
  }

  // Progressive drawing (docs/performance.md "Workbench"): while the camera moves (ViewMotion) the
  // fast pass draws a level-of-detail prefix of the map; the full frame follows kSettleSeconds
  // after the last move (needsFrame and waitSeconds wake the loop for it); frames that change
  // only the panels copy the view image cache.
  void drawView() {
    const Clock::time_point now = Clock::now();
    std::size_t budget = 0;
    if (bench_.isOpen()) {
      // A scripted run's screenshots are full quality: only its orbit may draw fast.
      const bool allowed = !scripted(script_) || script_.phase == ScriptPhase::kOrbit;
      const UiState& ui = bench_.ui();
      budget = motion_.frame(bench_.view().viewport(ui.view_width, ui.view_height).camera, mirror_.contentSerial(),
                             mirror_.mapSize(), now, allowed);
    }
    mirror_.setFastBudget(budget);
    const bool fast = mirror_.drawsFast();
    drawScene(bench_, gl_, mirror_, win_, &view_cache_);
    script_.map_drawn = mirror_.mapSize();  // height slice
    if (fast) {
      gl_.Finish();  // the fast pass's own time, to adapt the budget
      const double ms = msSince(now);
      motion_.fastFrameTook(ms);
      script_.fast_instances = mirror_.ellipsoidRenderer().lastDraw().point_instances;
      if (script_.phase == ScriptPhase::kOrbit) script_.fast_ms.push_back(ms);
    } else if (script_.view_fast && script_.phase == ScriptPhase::kOrbit) {
      script_.settle_ms = msSince(script_.last_move);  // the full frame after the orbit's last step
    }
    mirror_.setFastBudget(0);  // anything else drawn this frame (the view screenshot) is full quality
    script_.view_fast = fast;
  }

  // The window closed during the preparation: it goes at once, and the preparation stops within
  // one of its steps (a frame of the built-in scene), leaving nothing behind.
  void cancelPreparation() {
    glfwHideWindow(context_.window());
    *preparing_.cancel = true;
    preparing_.folder.wait();
    try {
      preparing_.folder.get();  // it may have finished meanwhile: then all is kept
    } catch (const std::exception&) {
      const std::size_t done = preparing_.progress->first, total = preparing_.progress->second;
      std::cerr << "vdmap: note: closed while " << preparing_.what << " ("
                << (total > 0 ? std::to_string(done) + " of " + std::to_string(total) + " frames done"
                              : "before its first frames")
                << "): nothing kept\n";
    }
  }

  void finishPreparation() {
    try {
      SequenceArgs args = preparing_.args;
      args.folder = preparing_.folder.get();
      bench_.files().open(args);
    } catch (const std::exception& e) {
      bench_.report(StatusLine::Kind::kError, preparing_.what + ": " + errorMessage(e));
    }
    startScript(script_, bench_);
  }

  // The preparation's progress as this frame shows it.
  void showPreparation() {
    win_.preparing = preparing_.folder.valid();
    win_.prepare_what = preparing_.what;
    win_.prepare_done = preparing_.progress->first;
    win_.prepare_total = preparing_.progress->second;
  }

  Workbench& bench_;
  GlfwWindowContext& context_;
  const render::Gl& gl_;
  KeyQueue& keys_;
  render::MapMirror mirror_;
  render::ViewCache view_cache_;  // progressive drawing
  render::ViewMotion motion_;
  WindowState win_;
  ScriptRun script_;
  Preparing preparing_;
  Seen last_seen_;
  int settle_frames_ = 2;
  int frames_drawn_ = 0;
};

}  // namespace

std::vector<int> parseKeyNames(const std::string& comma_separated) {
  std::vector<int> keys;
  std::stringstream in(comma_separated);
  for (std::string name; std::getline(in, name, ',');) {
    int ctrl = 0;
    if (name.rfind("ctrl+", 0) == 0) {
      ctrl = kCtrlKey;
      name = name.substr(5);
    }
    if (name.size() == 1 && name[0] >= 'a' && name[0] <= 'z') keys.push_back(GLFW_KEY_A + (name[0] - 'a'));
    else if (name == "space") keys.push_back(GLFW_KEY_SPACE);
    else if (name == "right") keys.push_back(GLFW_KEY_RIGHT);
    else if (name == "left") keys.push_back(GLFW_KEY_LEFT);
    else if (name == "f1") keys.push_back(GLFW_KEY_F1);
    else if (name == "esc") keys.push_back(GLFW_KEY_ESCAPE);
    else if (name == "pgup") keys.push_back(GLFW_KEY_PAGE_UP);
    else if (name == "pgdn") keys.push_back(GLFW_KEY_PAGE_DOWN);
    else
      throw std::invalid_argument("--press: unknown key '" + name +
                                  "' (a-z, space, right, left, f1, esc, pgup, pgdn; ctrl+ before any)");
    keys.back() |= ctrl;
  }
  return keys;
}

int runWorkbenchWindow(Workbench& bench, const ScriptOptions& script, const std::string& settings_file,
                       Preparation prepare) {
  Settings& s = bench.ui().settings;
  GlfwWindowContext context(s.window_width, s.window_height, "vdmap workbench");
  KeyQueue keys;
  glfwSetWindowUserPointer(context.window(), &keys);
  installInputCallbacks(context.window());
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  const std::string ini =
      settings_file.empty() ? "" : (std::filesystem::path(settings_file).parent_path() / "imgui.ini").string();
  ImGui::GetIO().IniFilename = ini.empty() ? nullptr : ini.c_str();
  ImGui::GetIO().ConfigInputTextCursorBlink = false;  // a blinking cursor would need frames while idle
  std::error_code ignored;  // ImGui writes imgui.ini at DestroyContext, before the settings make the folder
  if (!ini.empty()) std::filesystem::create_directories(std::filesystem::path(ini).parent_path(), ignored);
  ImGui::StyleColorsDark();
  // Dear ImGui draws a slider's value over its handle: a thin, see-through handle leaves the
  // digits under it readable.
  ImGuiStyle& style = ImGui::GetStyle();
  style.GrabMinSize = 6.f;
  style.Colors[ImGuiCol_SliderGrab].w = 0.45f;
  style.Colors[ImGuiCol_SliderGrabActive].w = 0.6f;
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
