#pragma once
// The workbench's window: a GLFW window with an OpenGL 3.3 core context, implementing
// render::Context so every renderer draws into it exactly as into the OSMesa context.
#include <string>

#include "render/context.h"

struct GLFWwindow;

namespace vdmap::app::gui {

/// Throws the error GlfwWindowContext throws when there is no display, without opening a window
/// or creating a context (GLFW is initialised and terminated again): a caller checks this before
/// long work that is only of use in a window.
void requireDisplay();

class GlfwWindowContext final : public render::Context {
 public:
  /// Opens a window of width x height and makes its context current. Throws std::runtime_error
  /// with GLFW's message when there is no display or no OpenGL 3.3 core context.
  GlfwWindowContext(int width, int height, const std::string& title);
  ~GlfwWindowContext() override;
  GlfwWindowContext(const GlfwWindowContext&) = delete;
  GlfwWindowContext& operator=(const GlfwWindowContext&) = delete;

  void makeCurrent() override;
  const render::Gl& gl() const override { return gl_; }
  GLFWwindow* window() const { return window_; }

 private:
  GLFWwindow* window_ = nullptr;
  render::Gl gl_;
};

}  // namespace vdmap::app::gui
