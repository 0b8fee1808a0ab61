#pragma once
// A rendering context: the one interface every renderer draws through. Two implementations:
// the OSMesa off-screen context here (tests, `vdmap render`, `vdmap synth`) and the GLFW window
// context in app/ (the workbench). Renderers only ever see `Context::gl()`.
#include <memory>
#include <string>

#include "render/gl.h"

namespace vdmap::render {

class Context {
 public:
  virtual ~Context() = default;
  /// Makes the context current on the calling thread (a context is used by one thread at a time).
  virtual void makeCurrent() = 0;
  /// The function table, valid while this context is current.
  virtual const Gl& gl() const = 0;
  /// "vendor / renderer / version", for logs and benchmark reports.
  std::string description() const;
};

/// Creates an OpenGL 3.3 core off-screen context with OSMesa (loaded at run time from
/// libOSMesa.so.8, or from $VDMAP_OSMESA_LIBRARY when set) and makes it current. Rendering
/// goes into Framebuffer objects. Throws std::runtime_error with a clear message when OSMesa is
/// not installed or cannot create a core context.
std::unique_ptr<Context> createOffscreenContext();

}  // namespace vdmap::render
