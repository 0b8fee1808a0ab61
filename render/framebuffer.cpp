#include "render/framebuffer.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "mapping/core/atomic_file.h"
#include "mapping/io/image_codec.h"

namespace vdmap::render {

Framebuffer::Framebuffer(const Gl& gl, int width, int height, bool with_float_target)
    : gl_(&gl), width_(width), height_(height), with_float_(with_float_target) {
  GLint limit = 0;
  gl.GetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &limit);
  const int max_side = std::min<int>(kMaxImageSide, limit > 0 ? limit : kMaxImageSide);
  if (width < 1 || height < 1 || width > max_side || height > max_side)
    throw std::invalid_argument("image size " + std::to_string(width) + "x" + std::to_string(height) +
                                " is outside 1x1 .. " + std::to_string(max_side) + "x" + std::to_string(max_side));
  gl.GenFramebuffers(1, &fbo_);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  auto attach = [&](GLuint& rb, GLenum format, GLenum attachment) {
    gl.GenRenderbuffers(1, &rb);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb);
    gl.RenderbufferStorage(GL_RENDERBUFFER, format, width, height);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER, rb);
  };
  attach(color_rb_, GL_RGBA8, GL_COLOR_ATTACHMENT0);
  attach(depth_rb_, GL_DEPTH_COMPONENT24, GL_DEPTH_ATTACHMENT);
  if (with_float_) attach(float_rb_, GL_RG32F, GL_COLOR_ATTACHMENT1);
  const GLenum status = gl.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("framebuffer " + std::to_string(width) + "x" + std::to_string(height) +
                             " is incomplete (status " + std::to_string(status) + ")");
  checkGl(gl, "creating a framebuffer");
}

Framebuffer::~Framebuffer() {
  gl_->DeleteFramebuffers(1, &fbo_);
  gl_->DeleteRenderbuffers(1, &color_rb_);
  gl_->DeleteRenderbuffers(1, &depth_rb_);
  if (float_rb_) gl_->DeleteRenderbuffers(1, &float_rb_);
}

void Framebuffer::bindAndClear(float r, float g, float b) {
  const Gl& gl = *gl_;
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl.DrawBuffers(with_float_ ? 2 : 1, bufs);
  gl.Viewport(0, 0, width_, height_);
  const float color[] = {r, g, b, 1.f}, zero[] = {0.f, 0.f, 0.f, 0.f}, one = 1.f;
  gl.ClearBufferfv(GL_COLOR, 0, color);
  if (with_float_) gl.ClearBufferfv(GL_COLOR, 1, zero);
  gl.ClearBufferfv(GL_DEPTH, 0, &one);
}

cv::Mat Framebuffer::read(GLenum attachment, int cv_type, GLenum format, GLenum type, const char* what) const {
  const Gl& gl = *gl_;
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl.ReadBuffer(attachment);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  cv::Mat image(height_, width_, cv_type);
  gl.ReadPixels(0, 0, width_, height_, format, type, image.data);
  checkGl(gl, what);
  cv::flip(image, image, 0);  // GL row 0 is the bottom of the image
  return image;
}

cv::Mat Framebuffer::readRgb() const {
  cv::Mat rgb;
  cv::cvtColor(read(GL_COLOR_ATTACHMENT0, CV_8UC4, GL_RGBA, GL_UNSIGNED_BYTE, "reading the colour buffer"), rgb,
               cv::COLOR_RGBA2RGB);  // alpha is dropped: screenshots are opaque
  return rgb;
}

cv::Mat Framebuffer::readFloat() const {
  if (!with_float_) throw std::logic_error("Framebuffer::readFloat without a float target");
  return read(GL_COLOR_ATTACHMENT1, CV_32FC2, GL_RG, GL_FLOAT, "reading the float buffer");
}

std::optional<float> readDepth(const Gl& gl, int x, int y) {
  if (x < 0 || y < 0) return std::nullopt;
  while (gl.GetError() != GL_NO_ERROR) {
  }
  float depth = 1.f;
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.ReadPixels(x, y, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &depth);
  if (gl.GetError() != GL_NO_ERROR) return std::nullopt;
  if (!std::isfinite(depth) || depth >= 1.f) return std::nullopt;
  return depth;
}

void writePng(const std::filesystem::path& file, const cv::Mat& rgb) { writeFileAtomically(file, encodePng(rgb)); }

}  // namespace vdmap::render
