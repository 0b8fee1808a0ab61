#pragma once
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "render/gpu_buffer.h"
#include "render/scene_types.h"
#include "render/shader_program.h"
#include "render/view_camera.h"

namespace vdmap::render {

struct EllipsoidStyle {
  float sigma = 2.f;            ///< drawn surface at this many standard deviations
  ColorMode color = ColorMode::kRgb;
  int sphere_subdivisions = 1;  ///< icosphere level of the instanced mesh (42 vertices at 1)
};

/// Draws ellipsoids as instanced, shaded icospheres scaled by the covariance's principal axes.
/// Geometry (centre + three scaled axes, 48 bytes) and colour (4 bytes) live in separate GPU
/// buffers: a colour-mode change re-sends colours only, update() re-sends one range.
class EllipsoidRenderer {
 public:
  EllipsoidRenderer(const Gl& gl, const EllipsoidStyle& style = {});
  ~EllipsoidRenderer();
  /// Replaces the whole set.
  void set(std::span<const EllipsoidInstance> ellipsoids);
  /// Rewrites instances [first, first + changed.size()) (an integrator's touched cells).
  /// In uncertainty/count modes the colour ramp keeps the range of the last set().
  void update(std::size_t first, std::span<const EllipsoidInstance> changed);
  /// Changes sigma (re-sends geometry) or colour mode (re-sends colours) when they differ.
  void setStyle(const EllipsoidStyle& style);
  void draw(const ViewCamera& view) const;
  std::size_t size() const { return count_; }

 private:
  const Gl* gl_;
  EllipsoidStyle style_;
  std::vector<EllipsoidInstance> instances_;  // kept to re-derive geometry/colours on a style change
  std::unique_ptr<ShaderProgram> program_;
  VertexArray vao_;
  GpuBuffer sphere_vertices_, sphere_indices_, geometry_, colors_;
  GLsizei index_count_ = 0;
  std::size_t count_ = 0;
};

/// The instance geometry of one ellipsoid: centre and the three principal axes scaled by
/// sigma * sqrt(eigenvalue) (12 floats). Exposed for tests.
std::array<float, 12> ellipsoidAxes(const EllipsoidInstance& e, float sigma);

}  // namespace vdmap::render
