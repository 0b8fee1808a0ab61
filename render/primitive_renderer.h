#pragma once
#include <memory>
#include <span>

#include "render/gpu_buffer.h"
#include "render/scene_types.h"
#include "render/shader_program.h"
#include "render/view_camera.h"

namespace vdmap::render {

/// Coloured points or line segments (one GL primitive type per object). Owns its buffers;
/// set() re-sends positions and colours.
class PrimitiveRenderer {
 public:
  PrimitiveRenderer(const Gl& gl, GLenum primitive);
  ~PrimitiveRenderer();
  void set(std::span<const glm::vec3> positions, std::span<const glm::u8vec3> colors);
  /// Point size or line width in pixels (lines wider than 1 px where the driver allows).
  void setSize(float pixels) { size_px_ = pixels; }
  /// true: drawn over everything (no depth test), e.g. a highlight.
  void setOnTop(bool on_top) { on_top_ = on_top; }
  void draw(const ViewCamera& view) const;
  std::size_t size() const { return count_; }

 private:
  const Gl* gl_;
  GLenum primitive_;
  std::unique_ptr<ShaderProgram> program_;
  VertexArray vao_;
  GpuBuffer positions_, colors_;
  std::size_t count_ = 0;
  float size_px_ = 1.f;
  bool on_top_ = false;
};

/// Ellipsoid centres as points, coloured like the ellipsoids.
class PointRenderer {
 public:
  explicit PointRenderer(const Gl& gl) : points_(gl, GL_POINTS) { points_.setSize(2.f); }
  /// The centres coloured as ellipsoidColors(ellipsoids, mode, height, slice).
  void set(std::span<const EllipsoidInstance> ellipsoids, ColorMode mode, const HeightFrame& height = {},
           const HeightSlice& slice = {});
  void setPointSize(float pixels) { points_.setSize(pixels); }
  void draw(const ViewCamera& view) const { points_.draw(view); }

 private:
  PrimitiveRenderer points_;
};

/// Line sets: keyframe frustums, covisibility edges, the trajectory (see scene_lines.h).
class LineRenderer {
 public:
  explicit LineRenderer(const Gl& gl) : lines_(gl, GL_LINES) {}
  void set(const ColoredLines& lines) { lines_.set(lines.positions, lines.colors); }
  void setWidth(float pixels) { lines_.setSize(pixels); }
  void setOnTop(bool on_top) { lines_.setOnTop(on_top); }
  void draw(const ViewCamera& view) const { lines_.draw(view); }

 private:
  PrimitiveRenderer lines_;
};

}  // namespace vdmap::render
