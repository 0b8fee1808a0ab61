#pragma once
// Golden-image comparison for the renderer's tests, through render/image_compare.h: the tests
// judge their renders by the metric users judge theirs.
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "render/image_compare.h"

namespace vdmap::test {

/// Tolerance: a pixel differs when any channel differs by more than kGoldenChannelTolerance
/// counts; an image matches when at most kGoldenPixelFraction of its pixels differ. These are
/// ImageTolerance's defaults (render/image_compare.h says why); for the 320x240 goldens 0.5 % is
/// 384 px, about one pixel along every edge of the test scenes.
constexpr int kGoldenChannelTolerance = 8;
constexpr double kGoldenPixelFraction = 0.005;
constexpr render::ImageTolerance kGoldenTolerance{.channel_counts = kGoldenChannelTolerance,
                                                  .pixel_share = kGoldenPixelFraction};

/// Compares an RGB image (CV_8UC3, RGB order) with assets/golden/NAME.png. A missing golden
/// writes NAME.png into the build's golden_out/ folder as a candidate and fails; a mismatch
/// writes NAME.actual.png and NAME.diff.png (render::diffImage) there and reports
/// ImageComparison::summary(): how many pixels differ, by how much and where.
::testing::AssertionResult matchesGolden(const cv::Mat& rgb, const std::string& name);

}  // namespace vdmap::test
