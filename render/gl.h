#pragma once
// The OpenGL function table of one context. GL headers are used for types and constants only
// (GL_GLEXT_PROTOTYPES is never defined), so nothing in render/ links a gl* symbol.
#include <functional>
#include <string>

#include <GL/glcorearb.h>

namespace vdmap::render {

/// A resolved entry point, as glfwGetProcAddress and OSMesaGetProcAddress return it.
using GlProc = void (*)();
/// Resolves a "gl..." name in the current context; returns null when unknown.
using GetProcFn = std::function<GlProc(const char*)>;

/// Pointers to every function of render/gl_functions.inc, called as `gl.Clear(...)`.
/// Valid only while the context that loaded it is current on the calling thread.
struct Gl {
#define X(ret, name, args) ret(APIENTRYP name) args = nullptr;
#include "render/gl_functions.inc"
#undef X
};

/// Resolves the table in the current context. Throws std::runtime_error naming the first
/// function the context does not provide.
Gl loadGl(const GetProcFn& get_proc);

/// Throws std::runtime_error("<where>: OpenGL error 0x...") when the context has an error set.
void checkGl(const Gl& gl, const std::string& where);

}  // namespace vdmap::render
