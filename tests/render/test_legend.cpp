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
      n += p[3] == 255 && std::abs(p[0] - c.r) <= tolerance && std::abs(p[1] - c.g) <= tolerance &&
           std::abs(p[2] - c.b) <= tolerance;
    }
  return n;
}

float deltaE(const glm::u8vec3& a, const glm::u8vec3& b) { return glm::length(srgbToLab(a) - srgbToLab(b)); }

TEST(Colormap, TheKeyframePaletteIsTheGeneratedOne) {
  const std::vector<glm::u8vec3> generated = generateKeyframePalette();
  ASSERT_EQ(generated.size(), static_cast<std::size_t>(kKeyframePaletteSize));
  std::string table;  // render/keyframe_palette.inc, should it need regenerating
  for (const glm::u8vec3& c : generated)
    table.append("{")
        .append(std::to_string(c.r))
        .append(", ")
        .append(std::to_string(c.g))
        .append(", ")
        .append(std::to_string(c.b))
        .append("},\n");  // append: GCC 12 warns (-Wrestrict) on "{" + string
  for (int k = 0; k < kKeyframePaletteSize; ++k)
    ASSERT_EQ(keyframeColor(k), generated[static_cast<std::size_t>(k)]) << "K" << k << "; the table:\n" << table;
}

TEST(Colormap, First64KeyframeColoursAreAtLeast20DeltaEApart) {
  float closest = INFINITY;
  for (int a = 0; a < kKeyframePaletteSize; ++a) {
    const float lightness = srgbToLab(keyframeColor(a)).x;
    EXPECT_TRUE(lightness >= 44.5f && lightness <= 85.5f) << "K" << a << " L " << lightness;
    for (int b = a + 1; b < kKeyframePaletteSize; ++b)
      closest = std::min(closest, deltaE(keyframeColor(a), keyframeColor(b)));
  }
  EXPECT_GE(closest, 20.f);
}

TEST(Colormap, KAndKPlus13Differ) {
  // The golden-ratio hue steps made k and k + 13 (12 degrees of hue) and k + 21 near-repeats.
  for (int k = 0; k + 21 < kKeyframePaletteSize; ++k)
    for (int step : {1, 13, 21})
      EXPECT_GE(deltaE(keyframeColor(k), keyframeColor(k + step)), 20.f) << "K" << k << "+" << step;
  for (int k = 0; k < 128; ++k) EXPECT_GE(deltaE(keyframeColor(k), keyframeColor(k + 64)), 8.f) << "K" << k << "+64";
  // A later cycle is the palette with its lightness shifted.
  EXPECT_NEAR(srgbToLab(keyframeColor(64 + 5)).x - srgbToLab(keyframeColor(5)).x, 12.f, 2.5f);
  EXPECT_GE(deltaE(keyframeColor(5), keyframeColor(64 + 5)), 8.f);
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
  // Wide: every swatch fits in two rows.
  const cv::Mat wide = rasterizeLegend(legend, kDarkBackground, 1600);
  for (int k : {0, 7, 43}) EXPECT_GT(countColour(wide, keyframeColor(k)), 50) << "K" << k;
}

TEST(Legend, ManyKeyframesShowAStripWithEveryKeyframe) {
  // 42 keyframes in 320 px: two rows of swatches would hold 10; the strip holds a cell per id.
  for (const int n : {42, 150, 250}) {
    const Legend legend = legendFor(ColorMode::kKeyframe, std::nullopt, keyframes(n));
    const cv::Mat narrow = rasterizeLegend(legend, kDarkBackground, 320);
    EXPECT_LE(narrow.cols, 320) << n;
    for (int k = 0; k < n; ++k) ASSERT_GE(countColour(narrow, keyframeColor(k), 2), 3 * 10) << "K" << k << " of " << n;
    EXPECT_LT(narrow.rows, 140) << n << ": at most 3 rows of cells";
  }
}

TEST(Legend, StaysLeftOfTheUpLabel) {
  const float em = 13.f;
  const LegendPlace wide = legendPlace(1000, em);
  EXPECT_FALSE(wide.up_label_on_top);
  EXPECT_EQ(wide.max_width, 1000 - 254) << "16.5 em for the label, 3 em between";
  const Legend legend = legendFor(ColorMode::kKeyframe, std::nullopt, keyframes(300));
  EXPECT_LE(rasterizeLegend(legend, kDarkBackground, wide.max_width).cols, wide.max_width);
  // Narrower than 40 em: the legend takes the width, the label goes to the top.
  const LegendPlace narrow = legendPlace(500, em);
  EXPECT_TRUE(narrow.up_label_on_top);
  EXPECT_EQ(narrow.max_width, 500);
  EXPECT_LE(rasterizeLegend(legend, kDarkBackground, narrow.max_width).cols, 500);
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
