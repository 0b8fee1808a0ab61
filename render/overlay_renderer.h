#pragma once
// Blends an RGBA image (the legend) over the bound framebuffer, pixel for pixel, at a corner of
// the current viewport. Owns its GL objects; use with its context current.
#include <memory>

#include <opencv2/core.hpp>

#include "render/gl.h"
#include "render/gpu_buffer.h"

namespace vdmap::render {

class ShaderProgram;

class OverlayRenderer {
 public:
  explicit OverlayRenderer(const Gl& gl);
  ~OverlayRenderer();
  OverlayRenderer(const OverlayRenderer&) = delete;
  OverlayRenderer& operator=(const OverlayRenderer&) = delete;

  /// The image (CV_8UC4, RGBA order, row 0 on top); empty: draw nothing.
  void set(const cv::Mat& rgba);
  bool empty() const { return width_ == 0; }
  /// Draws the image with its top-left corner at (x, y) of the current viewport, image
  /// coordinates (row 0 on top); depth test off, alpha blended.
  void draw(int x, int y) const;

 private:
  const Gl* gl_;
  std::unique_ptr<ShaderProgram> program_;
  VertexArray vao_;
  GLuint texture_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace vdmap::render
