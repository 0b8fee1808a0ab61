#include "render/ellipsoid_renderer.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "render/colormap.h"
#include "render/icosphere.h"

namespace vdmap::render {
namespace {

constexpr std::size_t kGeometryStride = 12 * sizeof(float);

std::vector<float> geometryOf(std::span<const EllipsoidInstance> ellipsoids, float sigma) {
  std::vector<float> out(ellipsoids.size() * 12);
  for (std::size_t i = 0; i < ellipsoids.size(); ++i) {
    const auto axes = ellipsoidAxes(ellipsoids[i], sigma);
    std::copy(axes.begin(), axes.end(), out.begin() + 12 * i);
  }
  return out;
}

}  // namespace

std::array<float, 12> ellipsoidAxes(const EllipsoidInstance& e, float sigma) {
  Eigen::Matrix3f m;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) m(r, c) = e.cov[c][r];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver;
  solver.computeDirect(m);
  std::array<float, 12> out{e.mean.x, e.mean.y, e.mean.z};
  for (int k = 0; k < 3; ++k) {
    // Clamped at 1e-12 m^2: a flat cell (all points on a plane) is drawn as a disc.
    const float s = sigma * std::sqrt(std::max(solver.eigenvalues()(k), 1e-12f));
    const Eigen::Vector3f axis = solver.eigenvectors().col(k) * s;
    for (int j = 0; j < 3; ++j) out[3 + 3 * k + j] = std::isfinite(axis(j)) ? axis(j) : 0.f;
  }
  return out;
}

EllipsoidRenderer::EllipsoidRenderer(const Gl& gl, const EllipsoidStyle& style)
    : gl_(&gl), style_(style),
      program_(std::make_unique<ShaderProgram>(gl, "ellipsoid.vert", "shaded.frag")),
      vao_(gl), sphere_vertices_(gl), sphere_indices_(gl, GL_ELEMENT_ARRAY_BUFFER), geometry_(gl),
      colors_(gl) {
  const Icosphere sphere = makeIcosphere(style.sphere_subdivisions);
  vao_.bind();
  sphere_vertices_.upload(sphere.vertices.data(), sphere.vertices.size() * sizeof(glm::vec3));
  sphere_vertices_.attribute(0, 3, GL_FLOAT, false, sizeof(glm::vec3), 0);
  sphere_indices_.upload(sphere.triangles.data(), sphere.triangles.size() * sizeof(glm::uvec3));
  index_count_ = static_cast<GLsizei>(sphere.triangles.size() * 3);
  geometry_.upload(nullptr, 0);
  for (GLuint k = 0; k < 4; ++k)
    geometry_.attribute(1 + k, 3, GL_FLOAT, false, kGeometryStride, 3 * sizeof(float) * k, 1);
  colors_.upload(nullptr, 0);
  colors_.attribute(5, 4, GL_UNSIGNED_BYTE, true, 4, 0, 1);
  gl.BindVertexArray(0);
}

EllipsoidRenderer::~EllipsoidRenderer() = default;

void EllipsoidRenderer::set(std::span<const EllipsoidInstance> ellipsoids) {
  instances_.assign(ellipsoids.begin(), ellipsoids.end());
  count_ = instances_.size();
  const std::vector<float> geometry = geometryOf(instances_, style_.sigma);
  geometry_.upload(geometry.data(), geometry.size() * sizeof(float));
  const std::vector<glm::u8vec4> colors = ellipsoidColors(instances_, style_.color);
  colors_.upload(colors.data(), colors.size() * sizeof(glm::u8vec4));
}

void EllipsoidRenderer::update(std::size_t first, std::span<const EllipsoidInstance> changed) {
  if (first + changed.size() > count_) {
    std::vector<EllipsoidInstance> all = instances_;
    all.resize(first + changed.size());
    std::copy(changed.begin(), changed.end(), all.begin() + first);
    set(all);
    return;
  }
  std::copy(changed.begin(), changed.end(), instances_.begin() + first);
  const std::vector<float> geometry = geometryOf(changed, style_.sigma);
  geometry_.update(first * kGeometryStride, geometry.data(), geometry.size() * sizeof(float));
  std::vector<glm::u8vec4> colors;
  if (style_.color == ColorMode::kRgb || style_.color == ColorMode::kKeyframe) {
    colors = ellipsoidColors(changed, style_.color);
    colors_.update(first * 4, colors.data(), colors.size() * 4);
  } else {
    colors = ellipsoidColors(instances_, style_.color);  // a ramp depends on the whole set
    colors_.upload(colors.data(), colors.size() * 4);
  }
}

void EllipsoidRenderer::setStyle(const EllipsoidStyle& style) {
  const bool geometry_changed = style.sigma != style_.sigma;
  const bool colors_changed = style.color != style_.color;
  style_.sigma = style.sigma;
  style_.color = style.color;  // the sphere level is fixed at construction
  if (geometry_changed) {
    const std::vector<float> geometry = geometryOf(instances_, style_.sigma);
    geometry_.upload(geometry.data(), geometry.size() * sizeof(float));
  }
  if (colors_changed) {
    const std::vector<glm::u8vec4> colors = ellipsoidColors(instances_, style_.color);
    colors_.upload(colors.data(), colors.size() * 4);
  }
}

void EllipsoidRenderer::draw(const ViewCamera& view) const {
  if (count_ == 0) return;
  const Gl& gl = *gl_;
  program_->useWithView(view);
  vao_.bind();
  gl.DrawElementsInstanced(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr,
                           static_cast<GLsizei>(count_));
  gl.BindVertexArray(0);
}

}  // namespace vdmap::render
