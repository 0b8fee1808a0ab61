#include "app/window/script_driver.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "app/cli/error_text.h"
#include "app/window/measure_overlay.h"
#include "app/window/workbench_window.h"

namespace vdmap::app::gui {
namespace {

nlohmann::json toJson(const Rect& r) { return {r.x, r.y, r.w, r.h}; }

}  // namespace

std::optional<glm::vec3> ScriptedWindow::pointUnder(float x_px, float y_px) {
  return probeView(bench_, gl_, win_, x_px, y_px);
}

void ScriptedWindow::press(int key) {
  keys_.presses.emplace_back(key & ~kCtrlKey, key & kCtrlKey ? GLFW_MOD_CONTROL : 0);
}

void ScriptedWindow::saveScreenshot(const std::string& file) { gui::saveScreenshot(bench_, gl_, win_, file); }

// Where the panels and the 3-D view are and where the map projects, for the stats file.
nlohmann::json ScriptedWindow::layout() {
  const auto& global = win_.global;
  const UiState& ui = bench_.ui();
  const Layout& at = win_.layout;
  nlohmann::json layout = {
      {"window", {at.fb_width, at.fb_height}},
      {"viewport", toJson(at.view)},
      {"panels", {{"Sequence", toJson(at.left)}, {"Map", toJson(at.right)}, {"Status", toJson(at.status)}}},
      {"labels_cut", win_.check.labels_cut},
      {"help", toJson(at.help)},  // all zero while the help is closed
      {"up", {ui.camera.up.x, ui.camera.up.y, ui.camera.up.z}}};
  if (!global || global->map.ellipsoids.empty()) return layout;
  // What the view draws of the map (each ellipsoid's extent at the sigma, strays left out and
  // counted), so a cut is seen here.
  const render::DrawnBounds drawn = bench_.view().drawnMap();
  layout["map_strays"] = drawn.strays;
  if (drawn.empty) return layout;
  const render::FrameBox box(drawn.lo, drawn.hi, drawn.axes);
  const ViewportView v = bench_.view().viewport(ui.view_width, ui.view_height);
  float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (int c = 0; c < 8; ++c) {
    const glm::vec3 p = box.corner(c);
    const glm::vec4 q = v.camera.T_C_W * glm::vec4(p, 1.f);
    const float u = v.camera.fx * q.x / q.z + v.camera.cx + win_.layout.view.x + v.image.x;
    const float w = v.camera.fy * q.y / q.z + v.camera.cy + win_.layout.view.y + v.image.y;
    x0 = std::min(x0, u), y0 = std::min(y0, w), x1 = std::max(x1, u), y1 = std::max(y1, w);
  }
  layout["map_bbox_px"] = {x0, y0, x1, y1};
  return layout;
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
    bench.report(StatusLine::Kind::kError, errorMessage(e));
  }
}

void saveViewScreenshot(Workbench& bench, const render::Gl& gl, render::MapMirror& mirror, const WindowState& win,
                        const std::string& file) {
  const render::ViewSpec spec = bench.view().spec();
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
    const render::PixelRect r = bench.view().viewport(vw, vh).image;
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
    bench.report(StatusLine::Kind::kError, errorMessage(e));
  }
}

}  // namespace vdmap::app::gui
