#pragma once
#include <string>

#include <glm/glm.hpp>

#include "render/gl.h"
#include "render/view_camera.h"

namespace vdmap::render {

/// A linked GLSL program built from two embedded shaders (shaders/NAME). Owns the GL program;
/// create and destroy it with its context current.
class ShaderProgram {
 public:
  /// Throws std::runtime_error with the compiler log and the shader name on failure.
  ShaderProgram(const Gl& gl, const std::string& vertex_name, const std::string& fragment_name);
  ~ShaderProgram();
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  void use() const { gl_->UseProgram(id_); }
  void set(const char* name, int v) const { gl_->Uniform1i(loc(name), v); }
  void set(const char* name, float v) const { gl_->Uniform1f(loc(name), v); }
  void set(const char* name, const glm::vec2& v) const { gl_->Uniform2f(loc(name), v.x, v.y); }
  void set(const char* name, const glm::vec3& v) const { gl_->Uniform3f(loc(name), v.x, v.y, v.z); }
  void set(const char* name, const glm::vec4& v) const { gl_->Uniform4f(loc(name), v.x, v.y, v.z, v.w); }
  void set(const char* name, const glm::mat4& m) const;
  /// Uses the program with depth testing on and sets u_view (T_C_W) and u_proj of `view`.
  void useWithView(const ViewCamera& view) const;

 private:
  GLint loc(const char* name) const { return gl_->GetUniformLocation(id_, name); }
  const Gl* gl_;
  GLuint id_ = 0;
};

}  // namespace vdmap::render
