#pragma once
// The container view (paper Fig. 1): a keyframe's image in the middle of its 2W x 2H container
// (docs/method.md 2) with the keyframe's ellipsoids projected onto the image plane as filled 2-D
// ellipses, optionally with the cell grid.
#include <memory>
#include <optional>
#include <span>

#include <opencv2/core.hpp>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"
#include "render/gpu_buffer.h"
#include "render/scene_types.h"
#include "render/shader_program.h"
#include "render/texture.h"

namespace vdmap::render {

/// The projection of a 3-D Gaussian: centre and 2x2 covariance in container pixels
/// (u' = u + W/2, v' = v + H/2), and the depth of the mean in the keyframe (m).
struct ProjectedEllipse {
  glm::dvec2 center_px{0.0};
  glm::dmat2 cov_px2{1.0};
  double depth_m = 0.0;
};

/// Projects an ellipsoid (world frame) into keyframe K's container: mean through the pinhole,
/// covariance through the Jacobian of the projection at the mean (J Sigma_K J^T). Empty when the
/// mean is behind the camera (z <= 1 mm).
std::optional<ProjectedEllipse> projectEllipsoid(const EllipsoidInstance& e, const PinholeCamera& camera,
                                                 const Transform& T_K_W);

struct ContainerStyle {
  float sigma = 2.f;  ///< ellipses drawn out to this Mahalanobis radius
  ColorMode color = ColorMode::kRgb;
  int cell_size_px = 5;  ///< grid spacing (default s = 5 px)
  bool show_grid = false;
  bool show_bounds = false;  ///< the keyframe image's outline (yellow, about 1.5 output pixels)
  bool operator==(const ContainerStyle&) const = default;
};

/// Draws one keyframe's container into the bound framebuffer, scaled to its viewport.
class ContainerRenderer {
 public:
  explicit ContainerRenderer(const Gl& gl);
  ~ContainerRenderer();
  /// The keyframe: its RGB image (CV_8UC3, RGB order, camera size), intrinsics and pose.
  void setKeyframe(const cv::Mat& rgb, const PinholeCamera& camera, const Transform& T_W_K);
  /// The ellipsoids to project (world frame); re-sends the ellipse instances.
  void setEllipsoids(std::span<const EllipsoidInstance> ellipsoids, const ContainerStyle& style);
  /// Container size in pixels (2W x 2H).
  int containerWidth() const { return 2 * camera_.width; }
  int containerHeight() const { return 2 * camera_.height; }
  /// Draws into the bound framebuffer (whose viewport is `width` x `height`).
  void draw(int width, int height) const;

 private:
  const Gl* gl_;
  std::unique_ptr<ShaderProgram> background_, ellipses_;
  VertexArray background_vao_, ellipse_vao_;
  GpuBuffer instances_;
  Texture2D texture_;
  PinholeCamera camera_;
  Transform T_W_K_ = Transform::Identity();
  ContainerStyle style_;
  std::size_t count_ = 0;
};

}  // namespace vdmap::render
