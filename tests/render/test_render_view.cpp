// renderView (render/view_draw.h): the headless path that draws what the window draws, with the
// window's defaults (dark background, icosahedra, every layer, the legend).
#include <gtest/gtest.h>

#include "render/colormap.h"
#include "render/context.h"
#include "render/view_draw.h"
#include "tests/support/golden.h"
#include "tests/support/render_scenes.h"

namespace vdmap::render {
namespace {

class RenderView : public ::testing::Test {
 protected:
  void SetUp() override {
    context_ = createOffscreenContext();
    map_ = test::gridMap();
    graph_.camera = test::smallCamera();
    graph_.keyframes = test::ringOfKeyframes(6);
    graph_.edges = {{0, 1, 0.9f}, {1, 2, 0.7f}, {2, 3, 0.5f}, {0, 3, 0.1f}};
    graph_.trajectory = {graph_.keyframes[0], graph_.keyframes[1], graph_.keyframes[2]};
    graph_.current_keyframe = 2;
    graph_.tracked = true;
  }
  // The view of the grid and the ring of keyframes as `vdmap render` draws it.
  cv::Mat render(const ViewSpec& spec, int w = 320, int h = 240) {
    MapMirror mirror(context_->gl(), spec.sphere_level);
    mirror.setStyle(mirrorStyle(spec));
    mirror.setMap(1, map_);
    mirror.setGraph(1, spec.selected_keyframe, [&] { return graph_; });
    if (spec.layers.legend) mirror.setLegend(legendFor(spec.color, mirror.mapColorRange(), graph_), spec.background, w);
    ViewScene scene;
    scene.up = {0, 0, 1};
    // As `vdmap render` frames it (render_view.cpp).
    scene.bounds = frameBounds(
        drawnBounds(map_, spec.sigma, spec.draw(), spec.slice, heightFrame(map_, scene.up), frameAxes(map_, scene.up)),
        graph_);
    return renderView(context_->gl(), mirror, spec, scene, w, h);
  }
  std::unique_ptr<Context> context_;
  std::vector<Ellipsoid> map_;
  GraphScene graph_;
};

cv::Vec3b byte(const glm::vec3& c) {
  return {static_cast<uchar>(c.r * 255.f + 0.5f), static_cast<uchar>(c.g * 255.f + 0.5f),
          static_cast<uchar>(c.b * 255.f + 0.5f)};
}

bool near(const cv::Vec3b& a, const cv::Vec3b& b) {
  return std::abs(a[0] - b[0]) <= 1 && std::abs(a[1] - b[1]) <= 1 && std::abs(a[2] - b[2]) <= 1;
}

TEST_F(RenderView, TheDefaultGlobalViewIsDarkWithItsLegend) {
  const cv::Mat image = render(ViewSpec{});
  EXPECT_TRUE(near(image.at<cv::Vec3b>(0, 0), byte(kDarkBackground))) << image.at<cv::Vec3b>(0, 0);
  // The tracking key's "tracked" line, in the bottom-left corner.
  int key = 0;
  for (int y = image.rows - 60; y < image.rows; ++y)
    for (int x = 0; x < 60; ++x)
      key += near(image.at<cv::Vec3b>(y, x), {kTrajectoryColor.r, kTrajectoryColor.g, kTrajectoryColor.b});
  EXPECT_GT(key, 20) << "no tracking key at the bottom left";
  EXPECT_TRUE(test::matchesGolden(image, "view_default"));
}

TEST_F(RenderView, WhiteBackgroundChangesOnlyTheBackground) {
  ViewSpec spec;
  const cv::Mat dark = render(spec);
  spec.background = kWhiteBackground;
  const cv::Mat white = render(spec);
  // The legend's panel is the background at 60 %: leave its rectangle out.
  const cv::Mat legend = rasterizeLegend(legendFor(ColorMode::kRgb, std::nullopt, graph_), kDarkBackground, 320);
  const cv::Point at = legendOrigin(legend, 240);
  const cv::Rect panel(at.x, at.y, legend.cols, legend.rows);
  int background = 0, same = 0, changed_elsewhere = 0;
  for (int y = 0; y < dark.rows; ++y)
    for (int x = 0; x < dark.cols; ++x) {
      if (panel.contains({x, y})) continue;
      const cv::Vec3b d = dark.at<cv::Vec3b>(y, x), w = white.at<cv::Vec3b>(y, x);
      if (d == byte(kDarkBackground)) {
        background += w == byte(kWhiteBackground);
        changed_elsewhere += w != byte(kWhiteBackground);
      } else {
        same += d == w;
        changed_elsewhere += d != w;
      }
    }
  EXPECT_GT(background, 30000);
  EXPECT_GT(same, 2000) << "the map is drawn";
  EXPECT_EQ(changed_elsewhere, 0);
}

TEST_F(RenderView, EachLayerSwitchesOffAlone) {
  const cv::Mat all = render(ViewSpec{});
  for (bool ViewLayers::*layer :
       {&ViewLayers::frustums, &ViewLayers::graph, &ViewLayers::trajectory, &ViewLayers::legend}) {
    ViewSpec spec;
    spec.layers.*layer = false;
    const cv::Mat without = render(spec);
    EXPECT_GT(cv::countNonZero(cv::Mat(cv::abs(all - without)).reshape(1)), 10) << "a layer changed nothing";
  }
}

// Pixels on the image's border rows and columns that differ from `background` by more than 8 counts.
int borderPixelsOff(const cv::Mat& image, const glm::vec3& background) {
  const cv::Vec3b bg = byte(background);
  int off = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      if (y != 0 && y != image.rows - 1 && x != 0 && x != image.cols - 1) continue;
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
      off += std::abs(p[0] - bg[0]) > 8 || std::abs(p[1] - bg[1]) > 8 || std::abs(p[2] - bg[2]) > 8;
    }
  return off;
}

TEST_F(RenderView, AfterFramingNoMapPixelTouchesTheBorder) {
  // The grid with long ellipsoids at its corners, no cameras: the frame holds every surface drawn.
  for (const auto& [corner, sd] : {std::pair{Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(0.5, 0.01, 0.01)},
                                   std::pair{Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0.01, 0.5, 0.01)},
                                   std::pair{Eigen::Vector3d(1, -1, 0), Eigen::Vector3d(0.01, 0.01, 0.4)}}) {
    Ellipsoid e = map_.front();
    e.mean = corner;
    e.cov = sd.cwiseProduct(sd).asDiagonal();
    for (int i = 0; i < 3; ++i) map_.push_back(e);
  }
  graph_ = GraphScene{};
  ViewSpec spec;
  spec.layers.legend = false;
  for (const auto& [w, h] : {std::pair{320, 240}, std::pair{240, 320}})
    for (const float azimuth : {-60.f, 30.f}) {
      spec.orbit = Orbit{azimuth, 35.f, std::nullopt};
      const cv::Mat image = render(spec, w, h);
      EXPECT_GT(cv::countNonZero(cv::Mat(cv::abs(image - cv::Scalar(byte(kDarkBackground)))).reshape(1)), 2000)
          << "the map is drawn";
      EXPECT_EQ(borderPixelsOff(image, kDarkBackground), 0) << w << "x" << h << " azimuth " << azimuth;
    }
}

// --- height slice: height colours ---
// Two floors 2 m apart along a tilted up axis, side by side seen from above: coloured by height
// above the floor along that axis, each floor is one colour, the ramp's ends, and the legend
// gives the range.
TEST_F(RenderView, HeightColoursFollowTheUpAxisFromTheFloor) {
  const glm::vec3 up = glm::normalize(glm::vec3(0.5f, 0.f, 1.f));
  const glm::vec3 a = glm::normalize(glm::cross(glm::vec3(0, 1, 0), up)), b = glm::cross(up, a);
  std::vector<Ellipsoid> map;
  for (int floor = 0; floor < 2; ++floor)
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j) {
        const glm::vec3 p = (floor == 0 ? -1.1f : 0.1f) * a + 0.05f * static_cast<float>(i) * a +
                            0.05f * static_cast<float>(j - 10) * b + 2.f * static_cast<float>(floor) * up;
        Ellipsoid e;
        e.mean = {p.x, p.y, p.z};
        e.cov = Eigen::Matrix3d::Identity() * 4e-4;
        e.count = 10;
        map.push_back(e);
      }
  ViewSpec spec;
  spec.color = ColorMode::kHeight;
  spec.ellipsoids = false;  // centres: flat colours
  spec.layers = {.frustums = false, .graph = false, .trajectory = false, .groundtruth = false, .legend = false};
  ViewScene scene;
  scene.up = up;
  scene.height = heightFrame(map, up);
  EXPECT_NEAR(scene.height.floor_m, 0.f, 1e-4f);
  scene.bounds =
      frameBounds(drawnBounds(map, spec.sigma, spec.draw(), spec.slice, scene.height, frameAxes(map, up)), {});
  spec.look_at = LookAt{.eye = glm::vec3(0.f) + 6.f * up, .target = glm::vec3(0.f) + 1.f * up, .up = b};
  MapMirror mirror(context_->gl(), spec.sphere_level);
  mirror.setStyle(mirrorStyle(spec, scene.height));
  mirror.setMap(1, map);
  const cv::Mat image = renderView(context_->gl(), mirror, spec, scene, 320, 240);
  int low = 0, high = 0;
  const glm::u8vec3 c0 = colormap(0.f), c1 = colormap(1.f);
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      low += near(image.at<cv::Vec3b>(y, x), {c0.r, c0.g, c0.b});
      high += near(image.at<cv::Vec3b>(y, x), {c1.r, c1.g, c1.b});
    }
  EXPECT_GT(low, 200) << "the lower floor is the ramp's low end";
  EXPECT_GT(high, 200) << "the upper floor is the ramp's high end";
  const Legend legend = legendFor(ColorMode::kHeight, mirror.mapColorRange(), {});
  EXPECT_EQ(legend.ramp_title, "height above floor (m)");
  EXPECT_EQ(legend.ramp_lo, "0.00");
  EXPECT_EQ(legend.ramp_hi, "2.00");
  // A slice over the upper floor: the ramp spans it and the legend says so.
  spec.slice = {true, 1.5f, 2.5f};
  mirror.setStyle(mirrorStyle(spec, scene.height));
  EXPECT_EQ(legendFor(ColorMode::kHeight, mirror.mapColorRange(), {}).ramp_lo, "1.50");
}

}  // namespace
}  // namespace vdmap::render
