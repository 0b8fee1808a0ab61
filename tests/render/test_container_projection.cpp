// An ellipsoid drawn in the container view covers exactly the pixels its analytic 2-D
// projection (J Sigma J^T at the mean, k = sigma) predicts.
#include <cmath>

#include <gtest/gtest.h>

#include "render/container_renderer.h"
#include "render/context.h"
#include "render/framebuffer.h"
#include "tests/support/render_scenes.h"

namespace vdmap::render {
namespace {

TEST(ContainerProjection, FilledEllipseMatchesTheAnalyticProjection) {
  auto context = createOffscreenContext();
  const PinholeCamera camera = test::smallCamera();
  Transform T_W_K = Transform::Identity();
  T_W_K.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  T_W_K.translation() = Eigen::Vector3d(0.1, -0.2, 0.3);
  EllipsoidInstance e;
  const Eigen::Vector3d p_W = T_W_K * Eigen::Vector3d(0.15, -0.1, 1.5);  // in front, off-centre
  e.mean = {float(p_W.x()), float(p_W.y()), float(p_W.z())};
  e.cov = test::covariance(0.08f, 0.03f, 0.02f, 0.7f);
  e.rgb = {255, 255, 255};
  const float sigma = 2.f;

  ContainerRenderer container(context->gl());
  container.setKeyframe(cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(0, 0, 0)), camera, T_W_K);
  container.setEllipsoids(std::span(&e, 1), {.sigma = sigma});
  Framebuffer fb(context->gl(), container.containerWidth(), container.containerHeight());
  fb.bindAndClear(0.f, 0.f, 0.f);
  container.draw(fb.width(), fb.height());
  const cv::Mat image = fb.readRgb();

  // The expected ellipse, derived here rather than by the renderer's projectEllipsoid: the mean
  // through the camera model, shifted by the container's margin (the keyframe image is centred in
  // the 2W x 2H container), and the covariance through a central-difference Jacobian of it.
  const Transform T_K_W = T_W_K.inverse();
  const Eigen::Vector3d p_K = T_K_W * p_W;
  Eigen::Matrix<double, 2, 3> J;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d h = 1e-6 * Eigen::Vector3d::Unit(a);
    J.col(a) = (camera.project(p_K + h) - camera.project(p_K - h)) / 2e-6;
  }
  Eigen::Matrix3d cov_W;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) cov_W(r, c) = e.cov[c][r];
  const Eigen::Matrix2d cov2 = J * T_K_W.linear() * cov_W * T_K_W.linear().transpose() * J.transpose();
  const Eigen::Vector2d centre = camera.project(p_K) + Eigen::Vector2d(camera.width / 2, camera.height / 2);
  const glm::dmat2 inv = glm::inverse(glm::dmat2(cov2(0, 0), cov2(1, 0), cov2(0, 1), cov2(1, 1)));
  int covered = 0, wrong = 0, borderline = 0;
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u) {
      const glm::dvec2 d = glm::dvec2(u, v) - glm::dvec2(centre.x(), centre.y());
      const double m2 = glm::dot(d, inv * d);
      const bool drawn = image.at<cv::Vec3b>(v, u)[0] > 128;
      covered += drawn;
      // Pixels within 1% of the boundary may go either way (float vs double arithmetic).
      if (std::abs(m2 - sigma * sigma) < 0.01 * sigma * sigma) {
        ++borderline;
        continue;
      }
      wrong += drawn != (m2 < sigma * sigma);
    }
  EXPECT_GT(covered, 200) << "the ellipse should cover a few hundred pixels";
  EXPECT_EQ(wrong, 0) << "of " << covered << " covered pixels (" << borderline << " borderline skipped)";
}

}  // namespace
}  // namespace vdmap::render
