// The ellipsoid renderer's far level of detail (points for ellipsoids projecting below
// EllipsoidStyle::point_below_px) against the reference: every ellipsoid as the instanced mesh.
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "render/context.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "tests/support/render_scenes.h"

namespace vdmap::render {
namespace {

// 30 x 20 ellipsoids 10 px apart on a plane facing the camera at depth_m; at sigma 2 their
// half-axes project to 0.8 x 0.24 px in the image plane (rotated, 0.5 px along the ray) times `scale`.
std::vector<EllipsoidInstance> grid(const ViewCamera& view, float depth_m, float scale) {
  std::vector<EllipsoidInstance> out;
  const float px_m = depth_m / view.fx;  // metres per pixel at that depth
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 30; ++i) {
      EllipsoidInstance e;
      e.mean = {(10.f * i - 144.5f) * px_m, (10.f * j - 94.5f) * px_m, depth_m};  // on pixel centres
      e.cov = test::covariance(0.4f * scale * px_m, 0.12f * scale * px_m, 0.25f * scale * px_m, 0.3f * i);
      e.rgb = {static_cast<std::uint8_t>(60 + 6 * i), static_cast<std::uint8_t>(40 + 9 * j), 200};
      out.push_back(e);
    }
  return out;
}

cv::Mat render(const Gl& gl, const std::vector<EllipsoidInstance>& set, const ViewCamera& view, float point_below_px) {
  Framebuffer fb(gl, view.width, view.height);
  EllipsoidRenderer renderer(gl, {.point_below_px = point_below_px});
  renderer.set(set);
  fb.bindAndClear(0.f, 0.f, 0.f);
  renderer.draw(view);
  cv::Mat grey;
  cv::cvtColor(fb.readRgb(), grey, cv::COLOR_RGB2GRAY);
  return grey;
}

class EllipsoidLod : public ::testing::Test {
 protected:
  EllipsoidLod() {
    view_.width = 320;
    view_.height = 240;
    view_.cx = 159.5f;
    view_.cy = 119.5f;
  }
  cv::Mat draw(const std::vector<EllipsoidInstance>& set, float point_below_px) const {
    return render(context_->gl(), set, view_, point_below_px);
  }
  std::unique_ptr<Context> context_ = createOffscreenContext();
  ViewCamera view_;  // fx = fy = 525, identity pose: looking along +z
};

TEST_F(EllipsoidLod, SubPixelEllipsoidsAreAllDrawnAsSplats) {
  const auto set = grid(view_, 20.f, 1.f);
  const cv::Mat mesh = draw(set, 0.f);
  const cv::Mat splats = draw(set, 1.5f);
  // Every ellipsoid is drawn in both, at its centre pixel.
  for (const auto& e : set) {
    const int u = static_cast<int>(std::lround(view_.fx * e.mean.x / e.mean.z + view_.cx));
    const int v = static_cast<int>(std::lround(view_.fy * e.mean.y / e.mean.z + view_.cy));
    EXPECT_GT(splats.at<uchar>(v, u), 0) << u << "," << v;
    EXPECT_GT(mesh.at<uchar>(v, u), 0) << u << "," << v;
  }
  // Splats keep the footprint small: 1 to 5 px each (the 0.5 px^2 floor widens them slightly).
  const int splat_px = cv::countNonZero(splats);
  EXPECT_GE(splat_px, static_cast<int>(set.size()));
  EXPECT_LE(splat_px, 5 * static_cast<int>(set.size()));
  EXPECT_GT(cv::countNonZero(splats != mesh), 0) << "the splat image is the mesh image: no splat was drawn";
}

TEST_F(EllipsoidLod, SplatsCoverTheMeshSilhouette) {
  // Half-axes 3.2 x 1 px, rotated in the image plane: every ellipsoid as a splat covers about
  // the pixels of its mesh. Intersection over union measured 0.73 (the 0.5 px^2 floor widens
  // thin splats); mirrored splats (v flipped) give 0.36.
  const auto set = grid(view_, 20.f, 4.f);
  const cv::Mat mesh = draw(set, 0.f) > 0, splats = draw(set, 64.f) > 0;
  const double iou = static_cast<double>(cv::countNonZero(mesh & splats)) / cv::countNonZero(mesh | splats);
  std::printf("splat vs mesh silhouettes: IoU %.3f (%d vs %d px)\n", iou, cv::countNonZero(splats),
              cv::countNonZero(mesh));
  EXPECT_GT(iou, 0.6);
}

TEST_F(EllipsoidLod, LargeEllipsoidsAreUnchanged) {
  // Longest half-axes 8 px: above the default threshold, drawn exactly as without the LOD.
  const auto set = grid(view_, 2.f, 10.f);
  EXPECT_EQ(cv::countNonZero(draw(set, 0.f) != draw(set, EllipsoidStyle{}.point_below_px)), 0);
}

TEST_F(EllipsoidLod, AReusedRendererDrawsLikeAFreshOne) {
  // draw() keeps its selection of mesh-pass instances while the view and the instances stay
  // the same; after a colour change and a new view it must draw exactly what a new
  // renderer given the same state draws.
  const Gl& gl = context_->gl();
  Framebuffer fb(gl, view_.width, view_.height);
  auto shot = [&](const EllipsoidRenderer& renderer, const ViewCamera& view) {
    fb.bindAndClear(0.f, 0.f, 0.f);
    renderer.draw(view);
    return fb.readRgb();
  };
  auto fresh = [&](const std::vector<EllipsoidInstance>& set, const EllipsoidStyle& style, const ViewCamera& view) {
    EllipsoidRenderer renderer(gl, style);
    renderer.set(set);
    return shot(renderer, view);
  };
  auto same = [](const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF) == 0; };
  std::vector<EllipsoidInstance> set = grid(view_, 2.f, 10.f);  // mesh-pass sized
  EllipsoidRenderer reused(gl);
  reused.set(set);
  const cv::Mat before = shot(reused, view_);
  EXPECT_TRUE(same(before, shot(reused, view_)));

  const EllipsoidStyle by_keyframe{.color = ColorMode::kKeyframe};
  reused.setStyle(by_keyframe);
  // The first view after the change is 20 m away: every ellipsoid is a splat there and none is
  // selected for the mesh pass, so a selection kept from it would leave the next views empty.
  ViewCamera farther = view_;
  farther.T_C_W[3][2] += 18.f;
  EXPECT_TRUE(same(shot(reused, farther), fresh(set, by_keyframe, farther)));
  const cv::Mat recoloured = shot(reused, view_);
  EXPECT_FALSE(same(recoloured, before)) << "the colour change shows";
  EXPECT_TRUE(same(recoloured, fresh(set, by_keyframe, view_)));

  ViewCamera closer = view_;
  closer.T_C_W[3][2] -= 1.f;  // 1 m closer: some ellipsoids leave the view, the rest grow
  EXPECT_TRUE(same(shot(reused, closer), fresh(set, by_keyframe, closer)));
}

}  // namespace
}  // namespace vdmap::render
