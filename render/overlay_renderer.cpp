#include "render/overlay_renderer.h"

#include "render/shader_program.h"

namespace vdmap::render {

OverlayRenderer::OverlayRenderer(const Gl& gl)
    : gl_(&gl), program_(std::make_unique<ShaderProgram>(gl, "overlay.vert", "overlay.frag")), vao_(gl) {
  gl.GenTextures(1, &texture_);
}

OverlayRenderer::~OverlayRenderer() { gl_->DeleteTextures(1, &texture_); }

void OverlayRenderer::set(const cv::Mat& rgba) {
  width_ = height_ = 0;
  if (rgba.empty()) return;
  CV_Assert(rgba.type() == CV_8UC4);
  const cv::Mat image = rgba.isContinuous() ? rgba : rgba.clone();
  const Gl& gl = *gl_;
  gl.BindTexture(GL_TEXTURE_2D, texture_);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.cols, image.rows, 0, GL_RGBA, GL_UNSIGNED_BYTE, image.data);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  width_ = image.cols;
  height_ = image.rows;
}

void OverlayRenderer::draw(int x, int y) const {
  if (empty()) return;
  const Gl& gl = *gl_;
  GLint vp[4];
  gl.GetIntegerv(GL_VIEWPORT, vp);
  const float vw = static_cast<float>(vp[2]), vh = static_cast<float>(vp[3]);
  if (vw <= 0 || vh <= 0) return;
  gl.Disable(GL_DEPTH_TEST);
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  program_->use();
  program_->set("u_rect", glm::vec4(2.f * x / vw - 1.f, 1.f - 2.f * (y + height_) / vh, 2.f * (x + width_) / vw - 1.f,
                                    1.f - 2.f * y / vh));
  program_->set("u_origin", glm::vec2(vp[0] + x, vp[1] + vp[3] - y - height_));
  program_->set("u_image", 0);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, texture_);
  vao_.bind();
  gl.DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  gl.BindVertexArray(0);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  gl.Disable(GL_BLEND);
  gl.Enable(GL_DEPTH_TEST);
}

}  // namespace vdmap::render
