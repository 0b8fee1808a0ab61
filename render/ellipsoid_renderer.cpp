#include "render/ellipsoid_renderer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "mapping/core/parallel.h"
#include "render/colormap.h"
#include "render/icosphere.h"
#include "render/lod_order.h"

namespace vdmap::render {
namespace {

constexpr std::size_t kGeometryStride = 12 * sizeof(float);

// The instance geometry of one ellipsoid: centre and the three principal axes scaled by
// sigma * sqrt(eigenvalue) (12 floats).
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
  // A right-handed frame of axes (the ellipsoid is symmetric about each), so that every
  // instance's triangles keep the sphere's winding and back faces can be culled.
  const glm::vec3 a0(out[3], out[4], out[5]), a1(out[6], out[7], out[8]), a2(out[9], out[10], out[11]);
  if (glm::dot(glm::cross(a0, a1), a2) < 0.f)
    for (int j = 9; j < 12; ++j) out[j] = -out[j];
  return out;
}

// One eigen-decomposition per ellipsoid, on all cores (each writes its own slot): most of a new
// map's upload on the UI thread.
std::vector<float> geometryOf(std::span<const EllipsoidInstance> ellipsoids, float sigma) {
  std::vector<float> out(ellipsoids.size() * 12);
  parallelFor(0, ellipsoids.size(), [&](std::size_t i) {
    const auto axes = ellipsoidAxes(ellipsoids[i], sigma);
    std::copy(axes.begin(), axes.end(), out.begin() + 12 * static_cast<std::ptrdiff_t>(i));
  });
  return out;
}

}  // namespace

EllipsoidRenderer::EllipsoidRenderer(const Gl& gl, const EllipsoidStyle& style)
    : gl_(&gl), style_(style), program_(std::make_unique<ShaderProgram>(gl, "ellipsoid.vert", "shaded.frag")),
      point_program_(std::make_unique<ShaderProgram>(gl, "ellipsoid_point.vert", "ellipsoid_point.frag")),
      fast_program_(std::make_unique<ShaderProgram>(gl, "ellipsoid_fast.vert", "ellipsoid_fast.frag")), vao_(gl),
      near_vao_(gl), point_vao_(gl), fast_vao_(gl), sphere_vertices_(gl), sphere_indices_(gl, GL_ELEMENT_ARRAY_BUFFER),
      geometry_(gl), colors_(gl), lod_order_(gl, GL_ELEMENT_ARRAY_BUFFER), near_geometry_(gl), near_colors_(gl),
      far_indices_(gl, GL_ELEMENT_ARRAY_BUFFER) {
  const Icosphere sphere = makeIcosphere(style.sphere_subdivisions);
  index_count_ = static_cast<GLsizei>(sphere.triangles.size() * 3);
  sphere_vertices_.upload(sphere.vertices.data(), sphere.vertices.size() * sizeof(glm::vec3));
  sphere_indices_.upload(sphere.triangles.data(), sphere.triangles.size() * sizeof(glm::uvec3));
  // Mesh passes: the sphere per vertex, geometry and colour per instance; vao_ reads every
  // instance, near_vao_ the selection draw() makes per frame.
  auto mesh_vao = [this](const VertexArray& vao, GpuBuffer& geometry, GpuBuffer& colors) {
    vao.bind();
    sphere_vertices_.attribute(0, 3, GL_FLOAT, false, sizeof(glm::vec3), 0);
    sphere_indices_.bind();
    geometry.upload(nullptr, 0);
    for (GLuint k = 0; k < 4; ++k)
      geometry.attribute(1 + k, 3, GL_FLOAT, false, kGeometryStride, 3 * sizeof(float) * k, 1);
    colors.upload(nullptr, 0);
    colors.attribute(5, 4, GL_UNSIGNED_BYTE, true, 4, 0, 1);
  };
  mesh_vao(vao_, geometry_, colors_);
  mesh_vao(near_vao_, near_geometry_, near_colors_);
  // The point pass reads the full instance buffers, one vertex per ellipsoid.
  point_vao_.bind();
  for (GLuint k = 0; k < 4; ++k) geometry_.attribute(1 + k, 3, GL_FLOAT, false, kGeometryStride, 3 * sizeof(float) * k);
  colors_.attribute(5, 4, GL_UNSIGNED_BYTE, true, 4, 0);
  far_indices_.upload(nullptr, 0);
  // The fast pass: the same buffers, read through the level-of-detail order.
  fast_vao_.bind();
  for (GLuint k = 0; k < 4; ++k) geometry_.attribute(1 + k, 3, GL_FLOAT, false, kGeometryStride, 3 * sizeof(float) * k);
  colors_.attribute(5, 4, GL_UNSIGNED_BYTE, true, 4, 0);
  lod_order_.upload(nullptr, 0);
  gl.BindVertexArray(0);
}

EllipsoidRenderer::~EllipsoidRenderer() = default;

void EllipsoidRenderer::set(std::span<const EllipsoidInstance> ellipsoids, std::span<const std::uint32_t> lod_order) {
  near_key_.reset();
  instances_.assign(ellipsoids.begin(), ellipsoids.end());
  geometry_cpu_ = geometryOf(instances_, style_.sigma);
  geometry_.upload(geometry_cpu_.data(), geometry_cpu_.size() * sizeof(float));
  colors_cpu_ = ellipsoidColors(instances_, style_.color, style_.height, style_.slice);
  colors_.upload(colors_cpu_.data(), colors_cpu_.size() * sizeof(glm::u8vec4));
  if (lod_order.size() == instances_.size()) {
    lod_order_cpu_.assign(lod_order.begin(), lod_order.end());
  } else {
    std::vector<glm::vec3> centres(instances_.size());
    for (std::size_t i = 0; i < instances_.size(); ++i) centres[i] = instances_[i].mean;
    lod_order_cpu_ = render::lodOrder(centres);
  }
  gl_->BindVertexArray(0);  // the element buffer binding belongs to the bound VAO: fast_vao_'s
  fast_vao_.bind();
  lod_order_.upload(lod_order_cpu_.data(), lod_order_cpu_.size() * sizeof(std::uint32_t));
  gl_->BindVertexArray(0);
}

void EllipsoidRenderer::setStyle(const EllipsoidStyle& style) {
  const bool geometry_changed = style.sigma != style_.sigma;
  const bool colors_changed =
      style.color != style_.color ||
      (style.color == ColorMode::kHeight && (style.height != style_.height || style.slice != style_.slice));
  style_.sigma = style.sigma;
  style_.color = style.color;  // the sphere level is fixed at construction
  style_.height = style.height;
  style_.slice = style.slice;
  style_.point_below_px = style.point_below_px;
  if (geometry_changed || colors_changed) near_key_.reset();
  if (geometry_changed) {
    geometry_cpu_ = geometryOf(instances_, style_.sigma);
    geometry_.upload(geometry_cpu_.data(), geometry_cpu_.size() * sizeof(float));
  }
  if (colors_changed) {
    colors_cpu_ = ellipsoidColors(instances_, style_.color, style_.height, style_.slice);
    colors_.upload(colors_cpu_.data(), colors_cpu_.size() * 4);
  }
}

std::size_t EllipsoidRenderer::selectMeshInstances(const ViewCamera& view) const {
  // The shaders decide exactly which pass draws an instance; this selection only has to keep
  // every instance a pass may draw, so it uses 90% of the threshold for the mesh and 110% for
  // the splats. Instances wholly in front of the near plane (or behind the camera) are drawn by
  // neither pass; a splat whose centre lies in front of the near plane is clipped, and one whose
  // centre projects further outside the image than its half-width (`reach`) touches none of its
  // pixels.
  const glm::mat4& V = view.T_C_W;
  const MeshSelectionKey key{
      V, {view.fx, view.fy, view.cx, view.cy}, {view.width, view.height}, view.near_m, style_.point_below_px};
  if (near_key_ == key) return near_colors_cpu_.size();
  near_key_ = key;
  const glm::vec4 row_x(V[0][0], V[1][0], V[2][0], V[3][0]), row_y(V[0][1], V[1][1], V[2][1], V[3][1]);
  const glm::vec4 row_z(V[0][2], V[1][2], V[2][2], V[3][2]);
  const float focal_px = std::max(view.fx, view.fy), mesh_below = 0.9f * style_.point_below_px;
  const float splat_from = 1.1f * style_.point_below_px;
  // A splat's half-width: below 3 axes of at most 2 point_below_px each (off-axis perspective
  // doubles the first-order projection), sqrt(3 * 4 thr^2 + 0.5) + 0.5 < 3.5 thr + 1 px.
  const float reach = 4.f * style_.point_below_px + 8.f;
  const float u_lo = -reach, u_hi = static_cast<float>(view.width) + reach;
  const float v_lo = -reach, v_hi = static_cast<float>(view.height) + reach;
  // The image's four side planes through the eye (camera frame, unit normals pointing in, 2 px
  // outside the image): a mesh whose bounding sphere lies wholly beyond one has no pixel.
  const float w = static_cast<float>(view.width), h = static_cast<float>(view.height);
  const glm::vec3 sides[4] = {glm::normalize(glm::vec3(view.fx, 0.f, view.cx + 2.f)),
                              glm::normalize(glm::vec3(-view.fx, 0.f, w + 2.f - view.cx)),
                              glm::normalize(glm::vec3(0.f, view.fy, view.cy + 2.f)),
                              glm::normalize(glm::vec3(0.f, -view.fy, h + 2.f - view.cy))};
  near_geometry_cpu_.clear();
  near_colors_cpu_.clear();
  far_indices_cpu_.clear();
  for (std::size_t i = 0; i < instances_.size(); ++i) {
    const float* g = &geometry_cpu_[12 * i];
    const float z = row_z.x * g[0] + row_z.y * g[1] + row_z.z * g[2] + row_z.w;
    float r2 = 0.f;
    for (int k = 0; k < 3; ++k)
      r2 = std::max(r2, g[3 + 3 * k] * g[3 + 3 * k] + g[4 + 3 * k] * g[4 + 3 * k] + g[5 + 3 * k] * g[5 + 3 * k]);
    const float r = std::sqrt(r2);
    if (z + r < view.near_m) continue;
    const glm::vec3 c(row_x.x * g[0] + row_x.y * g[1] + row_x.z * g[2] + row_x.w,
                      row_y.x * g[0] + row_y.y * g[1] + row_y.z * g[2] + row_y.w, z);
    if (!(z > 0.f && focal_px * r < mesh_below * z) && glm::dot(sides[0], c) >= -r && glm::dot(sides[1], c) >= -r &&
        glm::dot(sides[2], c) >= -r && glm::dot(sides[3], c) >= -r) {
      near_geometry_cpu_.insert(near_geometry_cpu_.end(), g, g + 12);
      near_colors_cpu_.push_back(colors_cpu_[i]);
    }
    if (z < 0.999f * view.near_m || focal_px * r >= splat_from * z) continue;  // clipped, or a mesh
    const float u = view.fx * c.x / z + view.cx, v = view.fy * c.y / z + view.cy;
    if (u >= u_lo && u <= u_hi && v >= v_lo && v <= v_hi) far_indices_cpu_.push_back(static_cast<std::uint32_t>(i));
  }
  near_geometry_.upload(near_geometry_cpu_.data(), near_geometry_cpu_.size() * sizeof(float));
  near_colors_.upload(near_colors_cpu_.data(), near_colors_cpu_.size() * 4);
  gl_->BindVertexArray(0);  // the element buffer binding belongs to point_vao_
  point_vao_.bind();
  far_indices_.upload(far_indices_cpu_.data(), far_indices_cpu_.size() * sizeof(std::uint32_t));
  gl_->BindVertexArray(0);
  return near_colors_cpu_.size();
}

void EllipsoidRenderer::drawFast(const ViewCamera& view, std::size_t budget) const {
  const std::size_t count = std::min(budget, instances_.size());
  last_draw_ = {.fast = true, .point_instances = count};
  if (count == 0) return;
  const Gl& gl = *gl_;
  gl.Enable(GL_PROGRAM_POINT_SIZE);
  fast_program_->useWithView(view);
  fast_program_->set("u_focal_px", std::max(view.fx, view.fy));
  fast_program_->set("u_spread", std::sqrt(static_cast<float>(instances_.size()) / static_cast<float>(count)));
  fast_program_->set("u_max_px", 8.f);  // larger points cost llvmpipe more than they show
  fast_vao_.bind();
  gl.DrawElements(GL_POINTS, static_cast<GLsizei>(count), GL_UNSIGNED_INT, nullptr);
  gl.BindVertexArray(0);
}

void EllipsoidRenderer::draw(const ViewCamera& view) const {
  last_draw_ = {};
  if (instances_.empty()) return;
  const Gl& gl = *gl_;
  const float focal_px = std::max(view.fx, view.fy);
  const bool lod = style_.point_below_px > 0.f;
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t mesh_count = lod ? selectMeshInstances(view) : instances_.size();
  last_draw_.select_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  last_draw_.mesh_instances = mesh_count;
  last_draw_.point_instances = lod ? far_indices_cpu_.size() : 0;
  program_->useWithView(view);
  program_->set("u_focal_px", focal_px);
  program_->set("u_point_below_px", style_.point_below_px);
  (lod ? near_vao_ : vao_).bind();
  // The back faces lie behind the front ones (closed, convex, right-handed axes): culling them
  // halves the triangles llvmpipe sets up (docs/performance.md).
  gl.Enable(GL_CULL_FACE);
  gl.CullFace(GL_BACK);
  if (mesh_count > 0)
    gl.DrawElementsInstanced(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr, static_cast<GLsizei>(mesh_count));
  gl.Disable(GL_CULL_FACE);
  if (lod) {
    gl.Enable(GL_PROGRAM_POINT_SIZE);
    point_program_->useWithView(view);
    point_program_->set("u_focal_px", focal_px);
    point_program_->set("u_point_below_px", style_.point_below_px);
    point_program_->set("u_f_px", glm::vec2(view.fx, view.fy));
    point_vao_.bind();
    // Only the splats the selection kept, in index order (the picture of drawing them all).
    if (!far_indices_cpu_.empty())
      gl.DrawElements(GL_POINTS, static_cast<GLsizei>(far_indices_cpu_.size()), GL_UNSIGNED_INT, nullptr);
  }
  gl.BindVertexArray(0);
}

}  // namespace vdmap::render
