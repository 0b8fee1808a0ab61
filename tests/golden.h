#pragma once
// Golden-image comparison for the renderer's tests.
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace vdmap::test {

/// Tolerance: a pixel differs when any channel differs by more than kGoldenChannelTolerance
/// counts; an image matches when at most kGoldenPixelFraction of its pixels differ.
/// Why: llvmpipe is deterministic on one machine, but another Mesa version or CPU (AVX2 vs
/// SSE4 code paths) rounds shading by a count or two and may move a silhouette edge by one
/// pixel. 8 counts is well above shading rounding and well below any real change of colour
/// mode or lighting; 0.5% of a 320x240 golden (384 px) is about one pixel along every edge of
/// the test scenes, while a wrong camera, sigma or colour moves thousands of pixels.
constexpr int kGoldenChannelTolerance = 8;
constexpr double kGoldenPixelFraction = 0.005;

/// Compares an RGB image (CV_8UC3, RGB order) with assets/golden/NAME.png. A missing golden
/// writes NAME.png into the build's golden_out/ folder as a candidate and fails; a mismatch
/// writes NAME.actual.png and NAME.diff.png there and reports how many pixels differ by how much.
::testing::AssertionResult matchesGolden(const cv::Mat& rgb, const std::string& name);

}  // namespace vdmap::test
