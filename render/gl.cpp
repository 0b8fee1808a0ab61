#include "render/gl.h"

#include <cstdio>
#include <stdexcept>

namespace vdmap::render {

Gl loadGl(const GetProcFn& get_proc) {
  Gl gl;
#define X(ret, name, args)                                               \
  gl.name = reinterpret_cast<ret(APIENTRYP) args>(get_proc("gl" #name)); \
  if (!gl.name) throw std::runtime_error("OpenGL context lacks gl" #name " (need OpenGL 3.3 core)");
#include "render/gl_functions.inc"
#undef X
  return gl;
}

void checkGl(const Gl& gl, const std::string& where) {
  const GLenum err = gl.GetError();
  if (err == GL_NO_ERROR) return;
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", err);
  throw std::runtime_error(where + ": OpenGL error " + code);
}

}  // namespace vdmap::render
