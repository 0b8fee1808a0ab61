#include "render/container_renderer.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "render/colormap.h"

namespace vdmap::render {
namespace {

// One ellipse instance: centre (2), inverse covariance (a, b, c of [[a b][b c]]), half extents
// of its bounding box (2), depth (1), all in container pixels / metres; colour separately packed.
struct EllipseGpu {
  float center[2];
  float inv_cov[3];
  float half[2];
  float depth;
  std::uint8_t color[4];
};

}  // namespace

std::optional<ProjectedEllipse> projectEllipsoid(const EllipsoidInstance& e, const PinholeCamera& camera,
                                                 const Transform& T_K_W) {
  const Eigen::Vector3d p_W(e.mean.x, e.mean.y, e.mean.z);
  const Eigen::Vector3d p = T_K_W * p_W;
  if (p.z() <= 1e-3) return std::nullopt;
  Eigen::Matrix3d cov_W;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) cov_W(r, c) = e.cov[c][r];
  const Eigen::Matrix3d R = T_K_W.linear();
  const Eigen::Matrix3d cov_K = R * cov_W * R.transpose();
  Eigen::Matrix<double, 2, 3> J;
  J << camera.fx / p.z(), 0, -camera.fx * p.x() / (p.z() * p.z()), 0, camera.fy / p.z(),
      -camera.fy * p.y() / (p.z() * p.z());
  const Eigen::Matrix2d cov2 = J * cov_K * J.transpose();
  const Eigen::Vector2d uv = camera.project(p);
  ProjectedEllipse out;
  out.center_px = {uv.x() + camera.width / 2, uv.y() + camera.height / 2};
  out.cov_px2 = glm::dmat2(cov2(0, 0), cov2(1, 0), cov2(0, 1), cov2(1, 1));
  out.depth_m = p.z();
  return out;
}

ContainerRenderer::ContainerRenderer(const Gl& gl)
    : gl_(&gl),
      background_(std::make_unique<ShaderProgram>(gl, "container_background.vert", "container_background.frag")),
      ellipses_(std::make_unique<ShaderProgram>(gl, "ellipse2d.vert", "ellipse2d.frag")), background_vao_(gl),
      ellipse_vao_(gl), instances_(gl), texture_(gl) {
  ellipse_vao_.bind();
  instances_.upload(nullptr, 0);
  const std::size_t stride = sizeof(EllipseGpu);
  instances_.attribute(0, 2, GL_FLOAT, false, stride, offsetof(EllipseGpu, center), 1);
  instances_.attribute(1, 3, GL_FLOAT, false, stride, offsetof(EllipseGpu, inv_cov), 1);
  instances_.attribute(2, 2, GL_FLOAT, false, stride, offsetof(EllipseGpu, half), 1);
  instances_.attribute(3, 1, GL_FLOAT, false, stride, offsetof(EllipseGpu, depth), 1);
  instances_.attribute(4, 4, GL_UNSIGNED_BYTE, true, stride, offsetof(EllipseGpu, color), 1);
  gl.BindVertexArray(0);
}

ContainerRenderer::~ContainerRenderer() = default;

void ContainerRenderer::setKeyframe(const cv::Mat& rgb, const PinholeCamera& camera, const Transform& T_W_K) {
  if (rgb.type() != CV_8UC3 || rgb.cols != camera.width || rgb.rows != camera.height)
    throw std::invalid_argument("container view needs the keyframe's RGB image at the camera size");
  camera_ = camera;
  T_W_K_ = T_W_K;
  texture_.set(rgb, true);
}

void ContainerRenderer::setEllipsoids(std::span<const EllipsoidInstance> ellipsoids, const ContainerStyle& style) {
  style_ = style;
  const Transform T_K_W = T_W_K_.inverse();
  const std::vector<glm::u8vec4> colors = ellipsoidColors(ellipsoids, style.color);
  std::vector<EllipseGpu> gpu;
  gpu.reserve(ellipsoids.size());
  const double k = style.sigma;
  for (std::size_t i = 0; i < ellipsoids.size(); ++i) {
    const auto e = projectEllipsoid(ellipsoids[i], camera_, T_K_W);
    if (!e) continue;
    const glm::dmat2& c = e->cov_px2;
    const double det = c[0][0] * c[1][1] - c[0][1] * c[1][0];
    if (!(det > 1e-12)) continue;  // degenerate (seen edge-on as a line): nothing to fill
    EllipseGpu g{};
    g.center[0] = static_cast<float>(e->center_px.x);
    g.center[1] = static_cast<float>(e->center_px.y);
    g.inv_cov[0] = static_cast<float>(c[1][1] / det);
    g.inv_cov[1] = static_cast<float>(-c[0][1] / det);
    g.inv_cov[2] = static_cast<float>(c[0][0] / det);
    // The bounding box of the k-sigma ellipse, one pixel larger so edge pixels are tested.
    g.half[0] = static_cast<float>(k * std::sqrt(c[0][0]) + 1.0);
    g.half[1] = static_cast<float>(k * std::sqrt(c[1][1]) + 1.0);
    g.depth = static_cast<float>(e->depth_m);
    for (int j = 0; j < 4; ++j) g.color[j] = colors[i][j];
    gpu.push_back(g);
  }
  count_ = gpu.size();
  instances_.upload(gpu.data(), gpu.size() * sizeof(EllipseGpu));
}

void ContainerRenderer::draw(int width, int height) const {
  const Gl& gl = *gl_;
  const glm::vec2 container(containerWidth(), containerHeight());
  gl.Disable(GL_DEPTH_TEST);
  background_->use();
  background_->set("u_viewport", glm::vec2(width, height));
  background_->set("u_container", container);
  background_->set("u_image_offset", glm::vec2(camera_.width / 2, camera_.height / 2));
  background_->set("u_cell_size", style_.show_grid ? style_.cell_size_px : 0);
  background_->set("u_bounds_only", 0);
  background_->set("u_image", 0);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, texture_.id());
  background_vao_.bind();
  gl.DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  if (count_ > 0) {
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_LESS);
    ellipses_->use();
    ellipses_->set("u_container", container);
    ellipses_->set("u_sigma", style_.sigma);
    ellipse_vao_.bind();
    gl.DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(count_));
  }
  if (style_.show_bounds) {  // the image's outline over the ellipses, as the window's
    gl.Disable(GL_DEPTH_TEST);
    background_->use();
    background_->set("u_bounds_only", 1);
    background_vao_.bind();
    gl.DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  }
  gl.BindVertexArray(0);
}

}  // namespace vdmap::render
