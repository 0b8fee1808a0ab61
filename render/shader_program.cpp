#include "render/shader_program.h"

#include <stdexcept>
#include <string_view>

#include <glm/gtc/type_ptr.hpp>

#include "render/shader_sources.h"

namespace vdmap::render {
namespace {

GLuint compile(const Gl& gl, GLenum type, const std::string& name) {
  const std::string_view text = shaderSource(name);
  const GLchar* src = text.data();
  const GLint len = static_cast<GLint>(text.size());
  const GLuint id = gl.CreateShader(type);
  gl.ShaderSource(id, 1, &src, &len);
  gl.CompileShader(id);
  GLint ok = 0;
  gl.GetShaderiv(id, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    gl.GetShaderInfoLog(id, sizeof log, nullptr, log);
    gl.DeleteShader(id);
    throw std::runtime_error("shaders/" + name + " does not compile: " + log);
  }
  return id;
}

}  // namespace

ShaderProgram::ShaderProgram(const Gl& gl, const std::string& vertex_name, const std::string& fragment_name)
    : gl_(&gl) {
  const GLuint vs = compile(gl, GL_VERTEX_SHADER, vertex_name);
  const GLuint fs = compile(gl, GL_FRAGMENT_SHADER, fragment_name);
  id_ = gl.CreateProgram();
  gl.AttachShader(id_, vs);
  gl.AttachShader(id_, fs);
  gl.LinkProgram(id_);
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  GLint ok = 0;
  gl.GetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    gl.GetProgramInfoLog(id_, sizeof log, nullptr, log);
    gl.DeleteProgram(id_);
    throw std::runtime_error("shaders " + vertex_name + " + " + fragment_name + " do not link: " + log);
  }
}

ShaderProgram::~ShaderProgram() { gl_->DeleteProgram(id_); }

void ShaderProgram::set(const char* name, const glm::mat4& m) const {
  gl_->UniformMatrix4fv(loc(name), 1, GL_FALSE, glm::value_ptr(m));
}

void ShaderProgram::useWithView(const ViewCamera& view) const {
  gl_->Enable(GL_DEPTH_TEST);
  gl_->DepthFunc(GL_LESS);
  use();
  set("u_view", view.T_C_W);
  set("u_proj", view.projection());
}

}  // namespace vdmap::render
