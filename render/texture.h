#pragma once
#include <opencv2/core.hpp>

#include "render/gl.h"

namespace vdmap::render {

/// An RGB8 2-D texture (e.g. for Dear ImGui's Image). Owns its GL object; use with its
/// context current.
class Texture2D {
 public:
  explicit Texture2D(const Gl& gl);
  ~Texture2D();
  Texture2D(const Texture2D&) = delete;
  Texture2D& operator=(const Texture2D&) = delete;

  /// Replaces the image (CV_8UC3, RGB order); an empty image leaves the texture as it was.
  /// nearest: sampled without interpolation (pixels stay sharp when magnified).
  void set(const cv::Mat& rgb, bool nearest = false);
  GLuint id() const { return id_; }
  int width() const { return width_; }
  int height() const { return height_; }
  bool empty() const { return width_ == 0; }

 private:
  const Gl* gl_;
  GLuint id_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace vdmap::render
