// The legend over the 3-D view (render/legend.h): what it says and how it is drawn, the same in
// the window and `vdmap render`.
#include <gtest/gtest.h>

#include "render/colormap.h"
#include "render/legend.h"
#include "render/view_spec.h"

namespace vdmap::render {
namespace {

GraphScene keyframes(int n) {
  GraphScene graph;
  graph.keyframes.resize(static_cast<std::size_t>(n));
  return graph;
}

// Pixels of `image` (RGBA) whose colour is within `tolerance` counts of `c`, opaque.
int countColour(const cv::Mat& image, const glm::u8vec3& c, int tolerance = 10) {
  int n = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec4b p = image.at<cv::Vec4b>(y, x);
      n += p[3] == 255 && std::abs(p[0] - c.r) <= tolerance && std::abs(p[1] - c.g) <= tolerance && std::abs(p[2] - c.b) <= tolerance;
    }
  return n;
}

TEST(Legend, UncertaintyHasARampWithItsRangeInMetres) {
  const Legend legend = legendFor(ColorMode::kUncertainty, ColorRange{0.00087f, 0.1219f}, keyframes(3));
  EXPECT_EQ(legend.ramp_title, "largest std. deviation (log scale)");
  EXPECT_EQ(legend.ramp_lo, "0.87 mm");
  EXPECT_EQ(legend.ramp_hi, "121.9 mm");
  EXPECT_TRUE(legend.swatches.empty());
  const Legend count = legendFor(ColorMode::kCount, ColorRange{6, 840}, keyframes(3));
  EXPECT_EQ(count.ramp_title, "points per ellipsoid (log scale)");
  EXPECT_EQ(count.ramp_lo, "6");
  EXPECT_EQ(count.ramp_hi, "840");
  EXPECT_TRUE(legendFor(ColorMode::kRgb, std::nullopt, keyframes(3)).empty());
  // Drawn: both ends of the viridis ramp appear, the panel is the background at 60 %.
  const cv::Mat image = rasterizeLegend(legend, kDarkBackground, 1280);
  ASSERT_EQ(image.type(), CV_8UC4);
  EXPECT_GT(countColour(image, colormap(0.f)), 20);
  EXPECT_GT(countColour(image, colormap(1.f)), 20);
  EXPECT_EQ(image.at<cv::Vec4b>(1, 1)[3], 153);
  // Light text on dark, dark text on white.
  // (antialiased: the text's core is within 60 counts of its colour)
  EXPECT_GT(countColour(image, {230, 230, 230}, 60), 50);
  EXPECT_GT(countColour(rasterizeLegend(legend, kWhiteBackground, 1280), {30, 30, 30}, 60), 50);
}

TEST(Legend, KeyframeModeShowsOneSwatchPerKeyframeInTwoRows) {
  const Legend legend = legendFor(ColorMode::kKeyframe, std::nullopt, keyframes(44));
  EXPECT_EQ(legend.swatch_title, "keyframe colours");
  ASSERT_EQ(legend.swatches.size(), 44u);
  EXPECT_EQ(legend.swatches[43].text, "K43");
  EXPECT_EQ(legend.swatches[7].color, keyframeColor(7));
  // Wide: every swatch fits in two rows. Narrow: as many as fit, in two rows.
  const cv::Mat wide = rasterizeLegend(legend, kDarkBackground, 1600);
  const cv::Mat narrow = rasterizeLegend(legend, kDarkBackground, 320);
  for (int k : {0, 7, 43}) EXPECT_GT(countColour(wide, keyframeColor(k)), 50) << "K" << k;
  EXPECT_LE(narrow.cols, 320);
  EXPECT_EQ(narrow.rows, wide.rows) << "two rows of swatches either way";
  EXPECT_EQ(countColour(narrow, keyframeColor(43)), 0) << "K43 does not fit 320 px";
}

TEST(Legend, TheTrackingKeyNamesTheLinesShown) {
  GraphScene graph = keyframes(2);
  EXPECT_TRUE(legendFor(ColorMode::kRgb, std::nullopt, graph).empty()) << "ground-truth poses: no key";
  graph.tracked = true;
  graph.groundtruth.resize(1);
  graph.loops.push_back({0, 1, 1.f});
  const Legend all = legendFor(ColorMode::kRgb, std::nullopt, graph);
  ASSERT_EQ(all.lines.size(), 3u);
  EXPECT_EQ(all.lines[0], (LegendKey{kTrajectoryColor, "tracked"}));
  EXPECT_EQ(all.lines[1], (LegendKey{kGroundTruthColor, "ground truth"}));
  EXPECT_EQ(all.lines[2], (LegendKey{kLoopEdgeColor, "loop closure"}));
  EXPECT_EQ(legendFor(ColorMode::kRgb, std::nullopt, graph, true, false, true).lines.size(), 2u);
}

}  // namespace
}  // namespace vdmap::render
