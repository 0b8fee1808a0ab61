#pragma once
#include <cstddef>

#include "render/gl.h"

namespace vdmap::render {

/// One GL buffer object that grows as needed. upload() replaces the contents (re-allocating
/// only when the data outgrows the buffer). Owns the buffer; use with its context current.
class GpuBuffer {
 public:
  explicit GpuBuffer(const Gl& gl, GLenum target = GL_ARRAY_BUFFER) : gl_(&gl), target_(target) {
    gl.GenBuffers(1, &id_);
  }
  ~GpuBuffer() { gl_->DeleteBuffers(1, &id_); }
  GpuBuffer(const GpuBuffer&) = delete;
  GpuBuffer& operator=(const GpuBuffer&) = delete;

  void bind() const { gl_->BindBuffer(target_, id_); }
  void upload(const void* data, std::size_t bytes) {
    bind();
    if (bytes > capacity_ || bytes == 0) {
      gl_->BufferData(target_, static_cast<GLsizeiptr>(bytes), data, GL_DYNAMIC_DRAW);
      capacity_ = bytes;
    } else {
      gl_->BufferSubData(target_, 0, static_cast<GLsizeiptr>(bytes), data);
    }
  }
  /// Binds and describes float attribute `index` (components, stride and offset in bytes).
  void attribute(GLuint index, GLint components, GLenum type, bool normalized, std::size_t stride, std::size_t offset,
                 GLuint divisor = 0) const {
    bind();
    gl_->EnableVertexAttribArray(index);
    gl_->VertexAttribPointer(index, components, type, normalized ? GL_TRUE : GL_FALSE, static_cast<GLsizei>(stride),
                             reinterpret_cast<const void*>(offset));
    gl_->VertexAttribDivisor(index, divisor);
  }

 private:
  const Gl* gl_;
  GLenum target_;
  GLuint id_ = 0;
  std::size_t capacity_ = 0;
};

/// A vertex array object (RAII).
class VertexArray {
 public:
  explicit VertexArray(const Gl& gl) : gl_(&gl) { gl.GenVertexArrays(1, &id_); }
  ~VertexArray() { gl_->DeleteVertexArrays(1, &id_); }
  VertexArray(const VertexArray&) = delete;
  VertexArray& operator=(const VertexArray&) = delete;
  void bind() const { gl_->BindVertexArray(id_); }

 private:
  const Gl* gl_;
  GLuint id_ = 0;
};

}  // namespace vdmap::render
