#include "app/window/glfw_context.h"

#include <stdexcept>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace vdmap::app::gui {
namespace {
std::string glfwMessage() {
  const char* text = nullptr;
  glfwGetError(&text);
  return text ? text : "unknown GLFW error";
}

void initGlfw() {
  if (!glfwInit()) throw std::runtime_error("cannot open a window (is there a display?): " + glfwMessage());
}
}  // namespace

void requireDisplay() {
  initGlfw();
  glfwTerminate();
}

GlfwWindowContext::GlfwWindowContext(int width, int height, const std::string& title) {
  initGlfw();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  // A forward-compatible context refuses line widths above 1 px (core profile, "wide lines"
  // deprecated), so the window drew every graph line 1 px wide while `vdmap render`'s OSMesa
  // context, not forward-compatible, drew them 1.5 and 3 px: the same view, two pictures.
  // macOS only offers core profiles that are forward-compatible.
#ifdef __APPLE__
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
#endif
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    const std::string message = glfwMessage();
    glfwTerminate();
    throw std::runtime_error("cannot create an OpenGL 3.3 core window: " + message);
  }
  makeCurrent();
  glfwSwapInterval(1);
  gl_ = render::loadGl([](const char* name) { return reinterpret_cast<render::GlProc>(glfwGetProcAddress(name)); });
}

GlfwWindowContext::~GlfwWindowContext() {
  glfwDestroyWindow(window_);
  glfwTerminate();
}

void GlfwWindowContext::makeCurrent() { glfwMakeContextCurrent(window_); }

}  // namespace vdmap::app::gui
