#include "render/primitive_renderer.h"

#include <algorithm>
#include <vector>

#include "render/colormap.h"

namespace vdmap::render {

PrimitiveRenderer::PrimitiveRenderer(const Gl& gl, GLenum primitive)
    : gl_(&gl), primitive_(primitive), program_(std::make_unique<ShaderProgram>(gl, "colored.vert", "colored.frag")),
      vao_(gl), positions_(gl), colors_(gl) {
  vao_.bind();
  positions_.upload(nullptr, 0);
  positions_.attribute(0, 3, GL_FLOAT, false, sizeof(glm::vec3), 0);
  colors_.upload(nullptr, 0);
  colors_.attribute(1, 3, GL_UNSIGNED_BYTE, true, sizeof(glm::u8vec3), 0);
  gl.BindVertexArray(0);
}

PrimitiveRenderer::~PrimitiveRenderer() = default;

void PrimitiveRenderer::set(std::span<const glm::vec3> positions, std::span<const glm::u8vec3> colors) {
  count_ = std::min(positions.size(), colors.size());
  positions_.upload(positions.data(), count_ * sizeof(glm::vec3));
  colors_.upload(colors.data(), count_ * sizeof(glm::u8vec3));
}

void PrimitiveRenderer::draw(const ViewCamera& view) const {
  if (count_ == 0) return;
  const Gl& gl = *gl_;
  if (on_top_) gl.Disable(GL_DEPTH_TEST);
  else gl.Enable(GL_DEPTH_TEST);
  gl.Enable(GL_PROGRAM_POINT_SIZE);
  if (primitive_ == GL_LINES) {
    gl.LineWidth(size_px_);
    gl.GetError();  // core profiles may refuse widths > 1; the 1 px line is then drawn
  }
  program_->use();
  program_->set("u_view_proj", view.viewProjection());
  program_->set("u_point_size", size_px_);
  vao_.bind();
  gl.DrawArrays(primitive_, 0, static_cast<GLsizei>(count_));
  gl.BindVertexArray(0);
  if (on_top_) gl.Enable(GL_DEPTH_TEST);
}

void PointRenderer::set(std::span<const EllipsoidInstance> ellipsoids, ColorMode mode, const HeightFrame& height,
                        const HeightSlice& slice) {
  std::vector<glm::vec3> positions;
  std::vector<glm::u8vec3> colors;
  positions.reserve(ellipsoids.size());
  for (const auto& e : ellipsoids) positions.push_back(e.mean);
  for (const auto& c : ellipsoidColors(ellipsoids, mode, height, slice)) colors.emplace_back(c);
  points_.set(positions, colors);
}

}  // namespace vdmap::render
