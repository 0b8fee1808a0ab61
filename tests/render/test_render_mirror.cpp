// The workbench's GPU mirror (render/map_mirror.h) under OSMesa: what it draws (golden), that a
// generation already uploaded costs nothing, and that its container view is the renderer's.
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "render/colormap.h"
#include "render/context.h"
#include "render/map_mirror.h"
#include "tests/support/golden.h"
#include "tests/support/render_scenes.h"

namespace vdmap::render {
namespace {

using test::matchesGolden;

GraphScene ringScene() {
  GraphScene scene;
  scene.camera = test::smallCamera();
  scene.keyframes = test::ringOfKeyframes(6);
  scene.edges = {{0, 1, 0.9f}, {1, 2, 0.7f}, {2, 3, 0.5f}, {0, 3, 0.1f}};
  scene.trajectory = {scene.keyframes[0], scene.keyframes[1], scene.keyframes[2]};
  scene.current_keyframe = 2;
  scene.selected_keyframe = 1;
  return scene;
}

class MapMirrorTest : public ::testing::Test {
 protected:
  void SetUp() override { context_ = createOffscreenContext(); }
  const Gl& gl() const { return context_->gl(); }
  cv::Mat draw(const MapMirror& mirror, bool with_lines = true) {
    Framebuffer fb(gl(), 320, 240);
    fb.bindAndClear(0.13f, 0.13f, 0.15f);
    mirror.draw(view_, with_lines);
    return fb.readRgb();
  }
  std::unique_ptr<Context> context_;
  ViewCamera view_ = ViewCamera::lookAt({0.5f, -3.f, 3.f}, {0, 0, 0.5f}, {0, 0, 1}, 55.f, 320, 240);
};

TEST_F(MapMirrorTest, DrawsTheMapTheGraphAndThePickedEllipsoid) {
  MapMirror mirror(gl());
  const std::vector<Ellipsoid> map = test::gridMap();
  mirror.setMap(1, map);
  mirror.setGraph(1, 1, ringScene);
  mirror.setHighlight(map[7]);
  EXPECT_TRUE(matchesGolden(draw(mirror), "mirror_scene"));
  // Without the lines ("view from keyframe") and without the pick, fewer pixels are lit.
  const cv::Mat all = draw(mirror);
  mirror.setHighlight(std::nullopt);
  const cv::Mat no_pick = draw(mirror);
  const cv::Mat no_lines = draw(mirror, false);
  cv::Mat magenta;
  cv::inRange(all, cv::Scalar(250, 0, 250), cv::Scalar(255, 5, 255), magenta);
  EXPECT_GT(cv::countNonZero(magenta), 30) << "the picked ellipsoid's diamond";
  cv::inRange(no_pick, cv::Scalar(250, 0, 250), cv::Scalar(255, 5, 255), magenta);
  EXPECT_EQ(cv::countNonZero(magenta), 0) << "a cleared pick leaves no mark";
  cv::Mat diff;
  cv::absdiff(no_pick, no_lines, diff);
  cv::cvtColor(diff, diff, cv::COLOR_RGB2GRAY);
  EXPECT_GT(cv::countNonZero(diff), 200) << "the frustums, edges and trajectory";
}

TEST_F(MapMirrorTest, UploadsOnlyWhatANewGenerationChanged) {
  MapMirror mirror(gl());
  const std::vector<Ellipsoid> map = test::gridMap();
  int builds = 0;
  const auto build = [&] {
    ++builds;
    return ringScene();
  };
  for (int frame = 0; frame < 3; ++frame) {  // three UI frames showing the same snapshots
    mirror.setMap(1, map);
    mirror.setGraph(4, -1, build);
    mirror.setFrame(4, test::testCard(), cv::Mat(120, 160, CV_16U, cv::Scalar(1000)), 1000.0);
  }
  EXPECT_EQ(mirror.uploads().map, 1);
  EXPECT_EQ(mirror.uploads().graph, 1);
  EXPECT_EQ(mirror.uploads().frame, 1);
  EXPECT_EQ(builds, 1);
  EXPECT_EQ(mirror.mapSize(), map.size());
  EXPECT_EQ(mirror.rgbTexture().width(), 160);
  EXPECT_EQ(mirror.depthTexture().height(), 120);

  mirror.setMap(2, std::span(map).first(5));  // a rebuild
  EXPECT_EQ(mirror.uploads().map, 2);
  EXPECT_EQ(mirror.mapSize(), 5u);
  mirror.setGraph(4, 3, build);  // another keyframe selected: new lines
  EXPECT_EQ(builds, 2);
  MirrorStyle style;
  style.frustums = false;  // a toggle: new lines
  mirror.setStyle(style);
  mirror.setGraph(4, 3, build);
  EXPECT_EQ(builds, 3);
  style.color = ColorMode::kCount;  // colours only: the lines stay, the map is not re-sent
  mirror.setStyle(style);
  mirror.setGraph(4, 3, build);
  mirror.setMap(2, std::span(map).first(5));
  EXPECT_EQ(builds, 3);
  EXPECT_EQ(mirror.uploads().map, 2);
}

// Pixels of exactly `color` (lines are drawn unshaded, in their vertices' colour).
int pixelsOf(const cv::Mat& rgb, const glm::u8vec3& color) {
  cv::Mat mask;
  cv::inRange(rgb, cv::Scalar(color.r, color.g, color.b), cv::Scalar(color.r, color.g, color.b), mask);
  return cv::countNonZero(mask);
}

TEST_F(MapMirrorTest, LoopEdgesAndTheGroundTruthHaveTheirOwnColoursAndToggles) {
  MapMirror mirror(gl());
  mirror.setMap(1, test::gridMap());  // the paths are drawn over it
  int builds = 0;
  const auto build = [&] {
    ++builds;
    GraphScene scene = ringScene();
    scene.loops = {{0, 3, 1.f}};
    for (const Transform& T : scene.trajectory) scene.groundtruth.push_back(Eigen::Translation3d(0, 0, 0.3) * T);
    return scene;
  };
  mirror.setGraph(1, -1, build);
  const cv::Mat shown = draw(mirror);
  EXPECT_GT(pixelsOf(shown, kLoopEdgeColor), 40) << "the loop edge K0-K3";
  EXPECT_GT(pixelsOf(shown, kGroundTruthColor), 40) << "the ground-truth trajectory";
  EXPECT_GT(pixelsOf(shown, kTrajectoryColor), 40) << "the trajectory";
  MirrorStyle style;
  style.groundtruth = false;
  mirror.setStyle(style);
  mirror.setGraph(1, -1, build);
  EXPECT_EQ(pixelsOf(draw(mirror), kGroundTruthColor), 0);
  style.graph = false;  // loop edges belong to the graph
  mirror.setStyle(style);
  mirror.setGraph(1, -1, build);
  EXPECT_EQ(pixelsOf(draw(mirror), kLoopEdgeColor), 0);
  EXPECT_EQ(builds, 3);
  mirror.setGraph(1, -1, build, 1);  // another variant of the same snapshot (poses before an optimisation)
  EXPECT_EQ(builds, 4);
}

TEST_F(MapMirrorTest, ContainerViewIsTheContainerRenderersAndFollowsItsStyle) {
  // The scene of RenderGolden.ContainerView, through the mirror.
  MapMirror mirror(gl());
  std::vector<Ellipsoid> set = test::gridMap();
  for (auto& e : set) e.mean = {e.mean.x() * 0.8, e.mean.y(), 2.0 + e.mean.z()};
  const ContainerStyle style{.sigma = 2.f, .color = ColorMode::kRgb, .cell_size_px = 10, .show_grid = true};
  const PinholeCamera camera = test::smallCamera();
  mirror.setContainer(1, 0, test::testCard(), camera, Transform::Identity(), set, style);
  EXPECT_TRUE(matchesGolden(mirror.containerImage(), "container_view"));
  EXPECT_EQ(mirror.containerTexture().width(), 2 * camera.width);
  mirror.setContainer(1, 0, test::testCard(), camera, Transform::Identity(), set, style);
  EXPECT_EQ(mirror.uploads().container, 1);
  ContainerStyle by_count = style;
  by_count.color = ColorMode::kCount;
  mirror.setContainer(1, 0, test::testCard(), camera, Transform::Identity(), set, by_count);
  EXPECT_EQ(mirror.uploads().container, 2);
  mirror.setContainer(2, -1, cv::Mat(), camera, Transform::Identity(), {}, by_count);  // nothing selected
  EXPECT_TRUE(mirror.containerImage().empty());
}

TEST(MapMirrorColors, RangeAndDepthRampSayWhatTheLegendsShow) {
  std::vector<EllipsoidInstance> set(2);
  set[0].cov = glm::mat3(1e-6f);  // sigma 1 mm
  set[0].count = 3;
  set[1].cov = glm::mat3(4e-4f);  // sigma 2 cm
  set[1].count = 300;
  const auto u = colorRange(set, ColorMode::kUncertainty);
  ASSERT_TRUE(u);
  EXPECT_NEAR(u->lo, 1e-3f, 1e-6f);
  EXPECT_NEAR(u->hi, 2e-2f, 1e-6f);
  const auto n = colorRange(set, ColorMode::kCount);
  ASSERT_TRUE(n);
  EXPECT_EQ(n->lo, 3.f);
  EXPECT_EQ(n->hi, 300.f);
  EXPECT_FALSE(colorRange(set, ColorMode::kRgb));
  EXPECT_FALSE(colorRange({}, ColorMode::kCount));

  cv::Mat depth(1, 3, CV_16U);
  depth.at<std::uint16_t>(0) = 0;     // no measurement: black
  depth.at<std::uint16_t>(1) = 100;   // 0.1 m: the dark end
  depth.at<std::uint16_t>(2) = 6000;  // 6 m: the bright end
  const cv::Mat rgb = depthToRgb(depth, 1000.0, kDepthRampMaxM);
  EXPECT_EQ(rgb.at<cv::Vec3b>(0), cv::Vec3b(0, 0, 0));
  EXPECT_LT(cv::norm(rgb.at<cv::Vec3b>(1)), cv::norm(rgb.at<cv::Vec3b>(2)));
  EXPECT_GT(rgb.at<cv::Vec3b>(2)[0], 200);  // viridis ends yellow: red and green high
  EXPECT_GT(rgb.at<cv::Vec3b>(2)[1], 200);
}

}  // namespace
}  // namespace vdmap::render
