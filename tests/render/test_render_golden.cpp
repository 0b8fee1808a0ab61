// Golden images of the renderer (assets/golden/*.png, 320x240, OSMesa/llvmpipe). Tolerance and
// its reason: tests/support/golden.h.
#include <gtest/gtest.h>

#include "mapping/synth/builtin_scene.h"
#include "render/colormap.h"
#include "render/container_renderer.h"
#include "render/context.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "render/map_scene.h"
#include "render/mesh_renderer.h"
#include "render/primitive_renderer.h"
#include "tests/support/golden.h"
#include "tests/support/render_scenes.h"

namespace vdmap::render {
namespace {

using test::matchesGolden;

class RenderGolden : public ::testing::Test {
 protected:
  void SetUp() override { context_ = createOffscreenContext(); }
  const Gl& gl() const { return context_->gl(); }
  std::unique_ptr<Context> context_;
};

ViewCamera gridView() { return ViewCamera::lookAt({0.4f, -2.2f, 1.8f}, {0.f, 0.f, 0.f}, {0, 0, 1}, 50.f, 320, 240); }

TEST_F(RenderGolden, EllipsoidsGlobalView) {
  Framebuffer fb(gl(), 320, 240);
  EllipsoidRenderer ellipsoids(gl());
  ellipsoids.set(test::gridEllipsoids());
  fb.bindAndClear(1.f, 1.f, 1.f);
  ellipsoids.draw(gridView());
  EXPECT_TRUE(matchesGolden(fb.readRgb(), "ellipsoids_global"));
}

TEST_F(RenderGolden, EllipsoidsByUncertaintyWithCentres) {
  Framebuffer fb(gl(), 320, 240);
  EllipsoidRenderer ellipsoids(gl(), {.sigma = 1.f, .color = ColorMode::kUncertainty});
  const auto set = test::gridEllipsoids();
  ellipsoids.set(set);
  PointRenderer centres(gl());
  centres.set(set, ColorMode::kKeyframe);
  centres.setPointSize(4.f);
  fb.bindAndClear(0.1f, 0.1f, 0.1f);
  ellipsoids.draw(gridView());
  centres.draw(gridView());
  EXPECT_TRUE(matchesGolden(fb.readRgb(), "ellipsoids_uncertainty_centres"));
}

TEST_F(RenderGolden, ContainerView) {
  const PinholeCamera camera = test::smallCamera();
  ContainerRenderer container(gl());
  container.setKeyframe(test::testCard(), camera, Transform::Identity());
  std::vector<EllipsoidInstance> set = test::gridEllipsoids();
  for (auto& e : set) e.mean = {e.mean.x * 0.8f, e.mean.y, 2.f + e.mean.z};  // in front of K
  container.setEllipsoids(set, {.sigma = 2.f, .color = ColorMode::kRgb, .cell_size_px = 10, .show_grid = true});
  Framebuffer fb(gl(), container.containerWidth(), container.containerHeight());
  fb.bindAndClear(0.f, 0.f, 0.f);
  container.draw(fb.width(), fb.height());
  EXPECT_TRUE(matchesGolden(fb.readRgb(), "container_view"));
}

TEST_F(RenderGolden, FrustumsEdgesTrajectory) {
  const std::vector<Transform> keyframes = test::ringOfKeyframes(6);
  ColoredLines lines;
  for (std::size_t k = 0; k < keyframes.size(); ++k)
    addFrustum(lines, test::smallCamera(), keyframes[k], 0.3f, keyframeColor(static_cast<int>(k)));
  const std::vector<GraphEdge> edges = {{0, 1, 0.9f}, {1, 2, 0.7f}, {2, 3, 0.5f}, {3, 4, 0.3f},
                                        {4, 5, 0.2f}, {5, 0, 1.0f}, {0, 3, 0.1f}};
  addEdges(lines, keyframes, edges);
  std::vector<Transform> path;
  for (int i = 0; i <= 60; ++i) {
    Transform T = Transform::Identity();
    const double a = 2.0 * M_PI * i / 60;
    T.translation() = Eigen::Vector3d(1.2 * std::cos(a), 1.2 * std::sin(a), 1.0 + 0.1 * std::sin(3 * a));
    path.push_back(T);
  }
  addTrajectory(lines, path, {230, 230, 230});
  LineRenderer renderer(gl());
  renderer.set(lines);
  Framebuffer fb(gl(), 320, 240);
  fb.bindAndClear(0.1f, 0.1f, 0.12f);
  renderer.draw(ViewCamera::lookAt({0.5f, -3.f, 3.f}, {0, 0, 0.8f}, {0, 0, 1}, 55.f, 320, 240));
  EXPECT_TRUE(matchesGolden(fb.readRgb(), "frustums_edges"));
}

// A mesh on a `background` grey, seen from `eye` towards `target` (320x240, z up).
cv::Mat drawMesh(const Gl& gl, const ColoredMesh& mesh, float background, const glm::vec3& eye, const glm::vec3& target,
                 float fov_y_deg) {
  MeshRenderer renderer(gl);
  renderer.set(mesh);
  Framebuffer fb(gl, 320, 240);
  fb.bindAndClear(background, background, background);
  renderer.draw(ViewCamera::lookAt(eye, target, {0, 0, 1}, fov_y_deg, 320, 240));
  return fb.readRgb();
}

TEST_F(RenderGolden, Mesh) {
  EXPECT_TRUE(matchesGolden(drawMesh(gl(), test::cubeOnFloor(), 1.f, {2.2f, -2.8f, 2.2f}, {0, 0, 0.3f}, 50.f), "mesh"));
}

TEST_F(RenderGolden, BuiltinRoomMesh) {
  // The built-in room (the scene `vdmap` opens with) from a corner under the ceiling; its
  // texture tiles are 5 cm, so the golden also pins the texture generator.
  const ColoredMesh room = toColoredMesh(makeBuiltinScene({.frames = 2}).mesh);
  EXPECT_TRUE(
      matchesGolden(drawMesh(gl(), room, 0.f, {2.3f, -1.8f, 2.3f}, {-0.8f, 0.6f, 0.7f}, 70.f), "builtin_room_mesh"));
}

TEST_F(RenderGolden, ContextIsCoreProfile33OrNewer) {
  GLint major = 0, minor = 0;
  gl().GetIntegerv(GL_MAJOR_VERSION, &major);
  gl().GetIntegerv(GL_MINOR_VERSION, &minor);
  EXPECT_GE(major * 10 + minor, 33) << context_->description();
}

}  // namespace
}  // namespace vdmap::render
