#pragma once
// The window's side of the scripted run (app/workbench/script_run.h): what only the drawn frame
// can give it (the depth under a pixel, the screenshots, the panels' layout) and the keys it
// presses.
#include <optional>
#include <string>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "app/window/window_state.h"
#include "app/workbench/script_run.h"
#include "render/gl.h"

namespace vdmap::app::gui {

/// The scripted run's view of this window in the frame just drawn (after drawScene and the
/// panels, before the swap).
class ScriptedWindow : public ScriptWindow {
 public:
  ScriptedWindow(Workbench& bench, const render::Gl& gl, const WindowState& win, KeyQueue& keys)
      : bench_(bench), gl_(gl), win_(win), keys_(keys) {}
  std::optional<glm::vec3> pointUnder(float x_px, float y_px) override;
  void saveScreenshot(const std::string& file) override;
  nlohmann::json layout() override;
  void press(int key) override;  // parseKeyNames' code

 private:
  Workbench& bench_;
  const render::Gl& gl_;
  const WindowState& win_;
  KeyQueue& keys_;
};

/// Writes the window's back buffer as a PNG to `file`; the outcome goes to the status line.
void saveScreenshot(Workbench& bench, const render::Gl& gl, const WindowState& win, const std::string& file);
/// Writes the 3-D view's own image (ViewController::spec's view: the viewport, the letterbox of a
/// keyframe view, or the container drawn with the view's layers) as a PNG to `file`, read from
/// the back buffer after the map is drawn and before ImGui draws; the outcome goes to the status
/// line.
void saveViewScreenshot(Workbench& bench, const render::Gl& gl, render::MapMirror& mirror, const WindowState& win,
                        const std::string& file);

}  // namespace vdmap::app::gui
