#pragma once
#include <filesystem>
#include <optional>

#include <opencv2/core.hpp>

#include "render/gl.h"

namespace vdmap::render {

/// Largest width or height vdmap renders (also bounded by the context's GL_MAX_RENDERBUFFER_SIZE).
constexpr int kMaxImageSide = 16384;

/// An off-screen render target of a fixed size: RGBA8 colour, 24-bit depth and, optionally, a
/// second RG32F target (attachment 1) that shaders may write metric values into (the mesh
/// shader writes camera z in metres and the cosine of the incidence angle). Owns its GL objects.
class Framebuffer {
 public:
  /// Throws std::invalid_argument for a size outside [1, kMaxImageSide] or above the context's
  /// limit, std::runtime_error when the framebuffer is incomplete.
  Framebuffer(const Gl& gl, int width, int height, bool with_float_target = false);
  ~Framebuffer();
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  /// The GL framebuffer object (to bind it for reading, e.g. as a blit's source).
  GLuint id() const { return fbo_; }
  /// Binds for drawing, sets the viewport and clears colour (to r, g, b), depth and the
  /// float target (to 0, "no surface").
  void bindAndClear(float r, float g, float b);
  /// Colour as CV_8UC3 in RGB order, rows flipped so that row 0 is the top of the image.
  cv::Mat readRgb() const;
  /// The float target as CV_32FC2, rows flipped like readRgb. Requires with_float_target.
  cv::Mat readFloat() const;

 private:
  // One attachment read back as a cv::Mat of `cv_type`, rows flipped (row 0 on top).
  cv::Mat read(GLenum attachment, int cv_type, GLenum format, GLenum type, const char* what) const;
  const Gl* gl_;
  int width_, height_;
  bool with_float_;
  GLuint fbo_ = 0, color_rb_ = 0, float_rb_ = 0, depth_rb_ = 0;
};

/// The depth-buffer value (0 at near, 1 at far) of pixel (x, y) of the bound read framebuffer,
/// GL convention (x, y from the bottom-left); nullopt outside it or where nothing was drawn
/// (1.0, the cleared depth). The window's and the headless framebuffer alike; with
/// unproject() it gives the world point under the cursor.
std::optional<float> readDepth(const Gl& gl, int x, int y);

/// Writes an RGB (CV_8UC3, RGB order) image as PNG through a temporary name and a rename, so a
/// failed write leaves nothing behind. Throws std::runtime_error naming the file.
void writePng(const std::filesystem::path& file, const cv::Mat& rgb);

}  // namespace vdmap::render
