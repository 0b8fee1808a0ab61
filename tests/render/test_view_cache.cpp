// Progressive drawing of the 3-D view (docs/performance.md "Workbench") under OSMesa: the fast
// pass draws exactly its budget's prefix of the level-of-detail order, the view image cache
// copies an unchanged view (pixels equal to a fresh draw) and redraws after any change, and the
// motion clock asks for the full frame once the camera rests. Counts and pixels only.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>

#include "render/context.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "render/map_mirror.h"
#include "render/view_cache.h"
#include "render/view_draw.h"
#include "tests/support/render_scenes.h"

namespace vdmap::render {
namespace {

constexpr glm::vec3 kBackground{0.13f, 0.13f, 0.15f};

int differingPixels(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  return cv::countNonZero(diff.reshape(1) > 0);
}

class Progressive : public ::testing::Test {
 protected:
  void SetUp() override { context_ = createOffscreenContext(); }
  const Gl& gl() const { return context_->gl(); }
  // The mirror's view drawn into a fresh 320x240 framebuffer, through `cache` or directly.
  cv::Mat draw(const MapMirror& mirror, ViewCache* cache, const ViewCamera& view) {
    Framebuffer fb(gl(), view.width, view.height);
    fb.bindAndClear(0.f, 0.f, 0.f);
    const FramedView framed{view, {0, 0, view.width, view.height}};
    if (cache) cache->draw(mirror, framed, kBackground, {0, 0, view.width, view.height}, true, false);
    else drawMapView(gl(), mirror, framed, kBackground, {0, 0, view.width, view.height}, true, false);
    return fb.readRgb();
  }
  std::unique_ptr<Context> context_;
  ViewCamera view_ = ViewCamera::lookAt({0.5f, -3.f, 3.f}, {0, 0, 0.5f}, {0, 0, 1}, 55.f, 320, 240);
};

TEST_F(Progressive, FastPassDrawsTheBudgetPrefix) {
  // 30 x 20 tiny ellipsoids 10 px apart, facing the camera: each fast point is one pixel.
  ViewCamera view;
  view.width = 320, view.height = 240, view.cx = 159.5f, view.cy = 119.5f;
  std::vector<EllipsoidInstance> set;
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 30; ++i) {
      EllipsoidInstance e;
      e.mean = {(10.f * i - 144.5f) * 20.f / view.fx, (10.f * j - 94.5f) * 20.f / view.fy, 20.f};
      e.cov = test::covariance(1e-5f, 1e-5f, 1e-5f, 0.f);
      e.rgb = {255, 255, 255};
      set.push_back(e);
    }
  EllipsoidRenderer renderer(gl(), {});
  renderer.set(set);
  ASSERT_EQ(renderer.lodOrder().size(), set.size());
  Framebuffer fb(gl(), view.width, view.height);
  for (const std::size_t budget : {1u, 37u, 250u, 600u, 5000u}) {
    fb.bindAndClear(0.f, 0.f, 0.f);
    renderer.drawFast(view, budget);
    EXPECT_TRUE(renderer.lastDraw().fast);
    EXPECT_EQ(renderer.lastDraw().point_instances, std::min<std::size_t>(budget, set.size()));
    EXPECT_EQ(renderer.lastDraw().mesh_instances, 0u);
    const cv::Mat image = fb.readRgb();
    cv::Mat lit;
    cv::extractChannel(image, lit, 0);
    EXPECT_EQ(cv::countNonZero(lit), static_cast<int>(std::min<std::size_t>(budget, set.size()))) << budget;
    // The drawn points are the order's prefix: the first one's pixel is lit.
    const glm::vec3 first = set[renderer.lodOrder()[0]].mean;
    const int u = static_cast<int>(std::lround(view.fx * first.x / first.z + view.cx));
    const int v = static_cast<int>(std::lround(view.fy * first.y / first.z + view.cy));
    EXPECT_GT(image.at<cv::Vec3b>(v, u)[0], 0) << budget;
  }
  // An order made elsewhere (the mapping worker's) is taken as given; one of another size is not.
  const std::vector<std::uint32_t> own = renderer.lodOrder();
  const std::vector<std::uint32_t> reversed(own.rbegin(), own.rend());
  renderer.set(set, reversed);
  EXPECT_EQ(renderer.lodOrder(), reversed);
  renderer.set(set, std::span(reversed).first(5));
  EXPECT_EQ(renderer.lodOrder(), own);
  renderer.draw(view);
  EXPECT_FALSE(renderer.lastDraw().fast);
  EXPECT_EQ(renderer.lastDraw().point_instances, set.size());  // the full pass's splats: all of them
}

// The full pass sends the mesh pass only the near instances whose bounding sphere reaches the
// image, and the splat pass only the far ones whose splat may: the same picture as a wider image
// that draws them all, in fewer instances.
TEST_F(Progressive, MeshAndSplatPassesSkipWhatLiesOutsideTheImage) {
  ViewCamera narrow;
  narrow.width = 320, narrow.height = 240, narrow.cx = 159.5f, narrow.cy = 119.5f;
  ViewCamera wide = narrow;
  wide.width = 960, wide.cx = 479.5f;  // the narrow image is its middle third
  std::vector<EllipsoidInstance> set;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 90; ++i) {  // far and small: splats, spread over the wide image
      EllipsoidInstance e;
      // Centres 2.5 px outside the narrow image's left and right edges, too: their splats
      // (about 3 px of radius) reach into it.
      e.mean = {(10.f * i - 442.f) * 20.f / narrow.fx, (10.f * j - 115.f) * 20.f / narrow.fy, 20.f};
      e.cov = test::covariance(0.06f, 0.03f, 0.04f, 0.3f * i);
      e.rgb = {static_cast<std::uint8_t>(2 * i), static_cast<std::uint8_t>(10 * j), 200};
      set.push_back(e);
    }
  for (int i = 0; i < 9; ++i) {  // near and large: meshes, two centred 20 px outside the narrow image
    EllipsoidInstance e;
    e.mean = {-1.6f + 0.4f * i, 0.1f * (i % 3), 2.f};
    if (i == 2) e.mean.x = (300.f - 479.5f) * 2.f / narrow.fx;
    if (i == 6) e.mean.x = (660.f - 479.5f) * 2.f / narrow.fx;
    e.cov = test::covariance(0.08f, 0.05f, 0.03f, 0.5f * i);
    e.rgb = {250, static_cast<std::uint8_t>(25 * i), 40};
    set.push_back(e);
  }
  EllipsoidRenderer renderer(gl(), {});
  renderer.set(set);
  auto draw = [&](const ViewCamera& view) {
    Framebuffer fb(gl(), view.width, view.height);
    fb.bindAndClear(0.f, 0.f, 0.f);
    renderer.draw(view);
    return fb.readRgb();
  };
  const cv::Mat all = draw(wide);
  const auto wide_stats = renderer.lastDraw();
  const cv::Mat part = draw(narrow);
  const auto stats = renderer.lastDraw();
  EXPECT_EQ(wide_stats.mesh_instances, 9u);
  EXPECT_EQ(wide_stats.point_instances, 90u * 24u);
  EXPECT_LT(stats.mesh_instances, 9u);
  EXPECT_GE(stats.mesh_instances, 3u);
  EXPECT_LT(stats.point_instances, 90u * 24u / 2);
  EXPECT_GE(stats.point_instances, 30u * 24u);
  EXPECT_LE(differingPixels(part, all(cv::Rect(320, 0, 320, 240))), 48) << "the same picture (0 on Mesa 22 llvmpipe)";
  EXPECT_GT(cv::countNonZero(part.reshape(1) > 0), 5000) << "something is drawn";
}

TEST_F(Progressive, AnUnchangedViewIsBlittedNotRedrawn) {
  MapMirror mirror(gl());
  mirror.setMap(1, test::gridMap());
  ViewCache cache(gl());
  const cv::Mat fresh = draw(mirror, nullptr, view_);
  const cv::Mat first = draw(mirror, &cache, view_);
  const cv::Mat second = draw(mirror, &cache, view_);
  EXPECT_EQ(cache.redraws(), 1);
  EXPECT_EQ(cache.blits(), 1);
  EXPECT_GT(differingPixels(fresh, cv::Mat(fresh.size(), fresh.type(), cv::Scalar(33, 33, 38))), 1000)
      << "a map is drawn";
  EXPECT_EQ(differingPixels(first, fresh), 0);
  EXPECT_EQ(differingPixels(second, fresh), 0);
  // The depth comes along (the probe under the cursor reads it): the map's nearest point is
  // nearer than the far plane in the copy as in the cache.
  Framebuffer target(gl(), view_.width, view_.height);
  target.bindAndClear(0.f, 0.f, 0.f);
  cache.draw(mirror, {view_, {0, 0, view_.width, view_.height}}, kBackground, {0, 0, view_.width, view_.height}, true,
             false);
  ASSERT_TRUE(cache.depthCopied());
  std::vector<float> depth(static_cast<std::size_t>(view_.width * view_.height));
  gl().ReadPixels(0, 0, view_.width, view_.height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  EXPECT_LT(*std::min_element(depth.begin(), depth.end()), 0.999f);
}

TEST_F(Progressive, AnyUploadInvalidatesIt) {
  MapMirror mirror(gl());
  mirror.setMap(1, test::gridMap());
  ViewCache cache(gl());
  int expected = 0;
  auto expectRedrawn = [&](const char* what) {
    draw(mirror, &cache, view_);
    EXPECT_EQ(cache.redraws(), ++expected) << what;
    draw(mirror, &cache, view_);
    EXPECT_EQ(cache.redraws(), expected) << what << ", then unchanged";
  };
  expectRedrawn("first");
  std::vector<Ellipsoid> map = test::gridMap();
  map.pop_back();
  mirror.setMap(2, map);
  expectRedrawn("a new map");
  mirror.setMap(2, map);  // the same generation uploads nothing
  draw(mirror, &cache, view_);
  EXPECT_EQ(cache.redraws(), expected);
  mirror.setStyle({.sigma = 3.f});
  expectRedrawn("another sigma");
  mirror.setHighlight(map[0]);
  expectRedrawn("a highlight");
  mirror.setGraph(1, -1, [] { return GraphScene{}; });
  expectRedrawn("the graph");
  view_ = ViewCamera::lookAt({0.6f, -3.f, 3.f}, {0, 0, 0.5f}, {0, 0, 1}, 55.f, 320, 240);
  expectRedrawn("the camera");
  mirror.setFastBudget(5);
  expectRedrawn("the fast pass");
  mirror.setFastBudget(0);
  const cv::Mat full = draw(mirror, &cache, view_);
  EXPECT_EQ(cache.redraws(), ++expected) << "the full frame after the fast one";
  EXPECT_EQ(differingPixels(full, draw(mirror, nullptr, view_)), 0);
  cache.invalidate();
  expectRedrawn("invalidated");
}

TEST(ViewMotion, TheFullFrameIsDueOnceTheCameraRests) {
  using Clock = ViewMotion::Clock;
  using std::chrono::milliseconds;
  ViewMotion motion(500);  // a fixed budget: --fast-budget 500
  const Clock::time_point t0{};
  const ViewCamera a = ViewCamera::lookAt({0, -3, 3}, {0, 0, 0}, {0, 0, 1}, 55.f, 320, 240);
  const ViewCamera b = ViewCamera::lookAt({0.1f, -3, 3}, {0, 0, 0}, {0, 0, 1}, 55.f, 320, 240);
  EXPECT_EQ(motion.frame(a, 1, 10000, t0), 0u) << "the first frame";
  EXPECT_FALSE(motion.secondsToFullFrame(t0));
  EXPECT_EQ(motion.frame(b, 1, 10000, t0 + milliseconds(10)), 500u) << "the camera moved";
  EXPECT_TRUE(motion.moving(t0 + milliseconds(100)));
  ASSERT_TRUE(motion.secondsToFullFrame(t0 + milliseconds(100)));
  EXPECT_NEAR(*motion.secondsToFullFrame(t0 + milliseconds(100)), 0.06, 1e-9);
  EXPECT_EQ(*motion.secondsToFullFrame(t0 + milliseconds(400)), 0.0) << "overdue";
  EXPECT_EQ(motion.frame(b, 1, 10000, t0 + milliseconds(400)), 0u) << "at rest: full quality";
  EXPECT_FALSE(motion.secondsToFullFrame(t0 + milliseconds(400)));
  EXPECT_EQ(motion.frame(a, 2, 10000, t0 + milliseconds(410)), 0u) << "the map changed (and re-framed the view)";
  EXPECT_EQ(motion.frame(b, 2, 10000, t0 + milliseconds(420), false), 0u) << "not allowed (a screenshot)";
  EXPECT_EQ(motion.frame(a, 2, 400, t0 + milliseconds(430)), 0u) << "a map within the budget";
  motion.fastFrameTook(1000.0);
  EXPECT_EQ(motion.budget(), 500u) << "a fixed budget stays";

  ViewMotion adaptive;
  EXPECT_EQ(adaptive.budget(), ViewMotion::kStartBudget);
  adaptive.fastFrameTook(ViewMotion::kTargetMs * 1.25);
  EXPECT_EQ(adaptive.budget(), static_cast<std::size_t>(ViewMotion::kStartBudget * 0.8));
  for (int i = 0; i < 20; ++i) adaptive.fastFrameTook(1000.0);
  EXPECT_EQ(adaptive.budget(), ViewMotion::kMinBudget);
}

}  // namespace
}  // namespace vdmap::render
