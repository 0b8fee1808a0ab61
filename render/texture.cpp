#include "render/texture.h"

namespace vdmap::render {

Texture2D::Texture2D(const Gl& gl) : gl_(&gl) { gl.GenTextures(1, &id_); }

Texture2D::~Texture2D() { gl_->DeleteTextures(1, &id_); }

void Texture2D::set(const cv::Mat& rgb, bool nearest) {
  if (rgb.empty()) return;
  CV_Assert(rgb.type() == CV_8UC3);
  const cv::Mat image = rgb.isContinuous() ? rgb : rgb.clone();
  const Gl& gl = *gl_;
  gl.BindTexture(GL_TEXTURE_2D, id_);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image.cols, image.rows, 0, GL_RGB, GL_UNSIGNED_BYTE, image.data);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, nearest ? GL_NEAREST : GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, nearest ? GL_NEAREST : GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  width_ = image.cols;
  height_ = image.rows;
}

}  // namespace vdmap::render
