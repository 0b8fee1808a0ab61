// render/image_compare.h: the counts, the verdict at its edges, the diff picture, and the fast
// comparison against an obviously-correct per-pixel loop (on random images, on image views that
// are not continuous in memory and on the project's golden renders shifted by a pixel or two).
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "render/image_compare.h"
#include "tests/support/test_util.h"

namespace vdmap::render {
namespace {

namespace fs = std::filesystem;

// The oracle: the definition of the metric, one pixel at a time.
ImageComparison compareByLoop(const cv::Mat& expected, const cv::Mat& actual, const ImageTolerance& tolerance) {
  ImageComparison r;
  r.tolerance = tolerance;
  r.pixels = static_cast<long>(expected.rows) * expected.cols;
  int x0 = INT_MAX, y0 = INT_MAX, x1 = -1, y1 = -1;
  for (int y = 0; y < expected.rows; ++y)
    for (int x = 0; x < expected.cols; ++x) {
      const cv::Vec3b p = expected.at<cv::Vec3b>(y, x), q = actual.at<cv::Vec3b>(y, x);
      int d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(p[c]) - int(q[c])));
      r.worst = std::max(r.worst, d);
      if (d > 1) ++r.over1;
      if (d > 32) ++r.over32;
      if (d > tolerance.channel_counts) {
        ++r.differing;
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      }
    }
  r.share = double(r.differing) / double(r.pixels);
  if (r.differing > 0) r.where = cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  r.matches = r.share <= tolerance.pixel_share;
  return r;
}

void expectSameComparison(const ImageComparison& fast, const ImageComparison& slow, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(fast.pixels, slow.pixels);
  EXPECT_EQ(fast.differing, slow.differing);
  EXPECT_EQ(fast.over1, slow.over1);
  EXPECT_EQ(fast.over32, slow.over32);
  EXPECT_EQ(fast.worst, slow.worst);
  EXPECT_EQ(fast.share, slow.share);
  EXPECT_EQ(fast.where, slow.where);
  EXPECT_EQ(fast.matches, slow.matches);
}

cv::Mat uniform(int width, int height, cv::Vec3b rgb) {
  return cv::Mat(height, width, CV_8UC3, cv::Scalar(rgb[0], rgb[1], rgb[2]));
}

cv::Mat randomImage(int width, int height, uint64_t seed) {
  cv::Mat image(height, width, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

// `image` plus Gaussian noise of `sigma` counts on every channel, saturated to 0..255.
cv::Mat withNoise(const cv::Mat& image, double sigma, uint64_t seed) {
  cv::Mat noise(image.size(), CV_16SC3);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  cv::Mat out;
  cv::add(image, noise, out, cv::noArray(), CV_8UC3);
  return out;
}

// `image` moved right by dx and down by dy; the uncovered rows and columns keep their pixels.
cv::Mat shifted(const cv::Mat& image, int dx, int dy) {
  cv::Mat out = image.clone();
  const cv::Rect from(0, 0, image.cols - dx, image.rows - dy), to(dx, dy, image.cols - dx, image.rows - dy);
  image(from).copyTo(out(to));
  return out;
}

TEST(ImageCompare, IdenticalImagesMatch) {
  const cv::Mat image = randomImage(64, 48, 1);
  const ImageComparison c = compareImages(image, image.clone());
  EXPECT_TRUE(c.matches);
  EXPECT_EQ(c.pixels, 64 * 48);
  EXPECT_EQ(c.differing, 0);
  EXPECT_EQ(c.over1, 0);
  EXPECT_EQ(c.worst, 0);
  EXPECT_EQ(c.share, 0.0);
  EXPECT_TRUE(c.where.empty());
  EXPECT_EQ(c.summary(),
            "0 of 3072 pixels (0%, allowed 0.5%) differ by more than 8 counts; 0 by more than 1, 0 by more than 32, "
            "worst 0");
}

TEST(ImageCompare, AChannelOffByExactlyTheCountsStillMatches) {
  const cv::Mat expected = uniform(20, 10, {100, 150, 200});
  cv::Mat actual = uniform(20, 10, {100, 150, 208});  // blue off by 8 everywhere
  actual.at<cv::Vec3b>(2, 3) = {100, 159, 200};       // one pixel's green off by 9
  const ImageComparison c = compareImages(expected, actual, {.channel_counts = 8, .pixel_share = 0.0});
  EXPECT_EQ(c.differing, 1);
  EXPECT_EQ(c.over1, 200);
  EXPECT_EQ(c.worst, 9);
  EXPECT_EQ(c.where, cv::Rect(3, 2, 1, 1));
  EXPECT_FALSE(c.matches);                       // no pixel may differ at share 0
  actual.at<cv::Vec3b>(2, 3) = {100, 142, 208};  // green off by 8 the other way
  const ImageComparison at_the_edge = compareImages(expected, actual, {.channel_counts = 8, .pixel_share = 0.0});
  EXPECT_EQ(at_the_edge.differing, 0);
  EXPECT_TRUE(at_the_edge.matches);
}

TEST(ImageCompare, OnePixelOverTheShareFails) {
  // 0.5 % of 320 x 240 is 384 pixels: 384 differing pixels match, 385 do not.
  const cv::Mat expected = uniform(320, 240, {40, 40, 40});
  cv::Mat actual = expected.clone();
  for (int i = 0; i < 384; ++i) actual.at<cv::Vec3b>(10 + i / 100, 7 + i % 100) = {40, 40, 49};
  const ImageComparison at_the_share = compareImages(expected, actual);
  EXPECT_EQ(at_the_share.differing, 384);
  EXPECT_TRUE(at_the_share.matches) << at_the_share.summary();
  actual.at<cv::Vec3b>(200, 300) = {0, 40, 40};
  const ImageComparison over = compareImages(expected, actual);
  EXPECT_EQ(over.differing, 385);
  EXPECT_FALSE(over.matches) << over.summary();
  EXPECT_EQ(over.worst, 40);
  EXPECT_EQ(over.over32, 1);
  EXPECT_EQ(over.where, cv::Rect(7, 10, 294, 191));  // x 7..300, y 10..200
  EXPECT_EQ(over.summary(),
            "385 of 76800 pixels (0.501%, allowed 0.5%) differ by more than 8 counts; 385 by more than 1, 1 by more "
            "than 32, worst 40, inside x 7..300 y 10..200");
}

bool isGrey(const cv::Vec3b& p) { return p[0] == p[1] && p[1] == p[2]; }

TEST(ImageCompare, DiffIsGreyWhereEqualAndRedWhereDifferent) {
  const cv::Vec3b colour{200, 100, 50};
  const cv::Mat expected = uniform(40, 30, colour);
  cv::Mat actual = expected.clone();
  actual(cv::Rect(10, 5, 3, 2)).setTo(cv::Scalar(0, 0, 0));  // 6 pixels beyond the tolerance
  actual.at<cv::Vec3b>(20, 30) = {208, 92, 58};              // within it
  const cv::Mat diff = diffImage(expected, actual);
  ASSERT_EQ(diff.type(), CV_8UC3);
  ASSERT_EQ(diff.size(), expected.size());

  const double luma = 0.299 * colour[0] + 0.587 * colour[1] + 0.114 * colour[2];
  const cv::Vec3b equal = diff.at<cv::Vec3b>(20, 30);
  EXPECT_TRUE(isGrey(equal));
  EXPECT_NEAR(equal[0], 64 + luma / 2, 1.0);  // half contrast: dark and light stay readable under red

  const cv::Vec3b red{255, 0, 0}, yellow{255, 255, 0};
  EXPECT_EQ(diff.at<cv::Vec3b>(5, 10), red);
  EXPECT_EQ(diff.at<cv::Vec3b>(6, 12), red);
  // The box runs just outside the differing pixels: x 9..13, y 4..7.
  EXPECT_EQ(diff.at<cv::Vec3b>(4, 9), yellow);
  EXPECT_EQ(diff.at<cv::Vec3b>(7, 13), yellow);
  EXPECT_EQ(diff.at<cv::Vec3b>(4, 11), yellow);
  EXPECT_EQ(diff.at<cv::Vec3b>(6, 9), yellow);
  long reds = 0, yellows = 0, greys = 0;  // every pixel is one of the three
  for (int y = 0; y < diff.rows; ++y)
    for (int x = 0; x < diff.cols; ++x) {
      const cv::Vec3b p = diff.at<cv::Vec3b>(y, x);
      reds += p == red, yellows += p == yellow, greys += p == equal;
    }
  EXPECT_EQ(reds, 6);
  EXPECT_EQ(yellows, 5 * 4 - 6);
  EXPECT_EQ(greys, 40 * 30 - 6 - 14);

  const cv::Mat same = diffImage(expected, expected);
  EXPECT_EQ(cv::countNonZero(same.reshape(1) != equal[0]), 0) << "identical images give only grey";
}

TEST(ImageCompare, TheDiffBoxIsClippedAtTheBorderAndHidesNoRedPixel) {
  const cv::Mat expected = uniform(8, 6, {10, 10, 10});
  cv::Mat actual = expected.clone();
  actual.at<cv::Vec3b>(0, 0) = {255, 255, 255};
  const cv::Mat diff = diffImage(expected, actual);
  EXPECT_EQ(diff.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 0, 0));
  EXPECT_EQ(diff.at<cv::Vec3b>(0, 1), cv::Vec3b(255, 255, 0));
  EXPECT_EQ(diff.at<cv::Vec3b>(1, 0), cv::Vec3b(255, 255, 0));
  EXPECT_EQ(diff.at<cv::Vec3b>(1, 1), cv::Vec3b(255, 255, 0));
  EXPECT_TRUE(isGrey(diff.at<cv::Vec3b>(2, 2)));
}

TEST(ImageCompare, DifferentSizesAreRefusedNamingBoth) {
  const cv::Mat expected = uniform(320, 240, {0, 0, 0}), actual = uniform(160, 120, {0, 0, 0});
  try {
    compareImages(expected, actual);
    FAIL() << "images of different sizes were compared";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the expected image is 320x240, the actual one 160x120");
  }
  EXPECT_THROW(diffImage(expected, actual), std::invalid_argument);
}

TEST(ImageCompare, OtherTypesAndTolerancesOutOfRangeAreRefused) {
  const cv::Mat rgb = uniform(4, 4, {1, 2, 3});
  EXPECT_THROW(compareImages(cv::Mat(4, 4, CV_8UC4, cv::Scalar::all(0)), rgb), std::invalid_argument);
  EXPECT_THROW(compareImages(cv::Mat(4, 4, CV_8UC1, cv::Scalar::all(0)), cv::Mat(4, 4, CV_8UC1, cv::Scalar::all(0))),
               std::invalid_argument);
  EXPECT_THROW(compareImages(cv::Mat(), cv::Mat()), std::invalid_argument);
  EXPECT_THROW(compareImages(rgb, rgb, {.channel_counts = 256}), std::invalid_argument);
  EXPECT_THROW(compareImages(rgb, rgb, {.channel_counts = -1}), std::invalid_argument);
  EXPECT_THROW(compareImages(rgb, rgb, {.pixel_share = 1.5}), std::invalid_argument);
  EXPECT_THROW(compareImages(rgb, rgb, {.pixel_share = std::nan("")}), std::invalid_argument);
  EXPECT_NO_THROW(compareImages(rgb, rgb, {.channel_counts = 255, .pixel_share = 1.0}));
}

TEST(ImageCompare, TheFastComparisonEqualsAPerPixelLoop) {
  int matched = 0, failed = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const cv::Mat expected = randomImage(97, 61, seed);  // odd sizes: no whole SIMD rows
    const cv::Mat actual = withNoise(expected, 2.0 * seed, 100 + seed);
    for (const ImageTolerance tolerance :
         {ImageTolerance{}, ImageTolerance{0, 0.0}, ImageTolerance{3, 0.2}, ImageTolerance{40, 0.01}}) {
      const std::string what = "seed " + std::to_string(seed) + ", counts " + std::to_string(tolerance.channel_counts);
      const ImageComparison fast = compareImages(expected, actual, tolerance);
      expectSameComparison(fast, compareByLoop(expected, actual, tolerance), what);
      (fast.matches ? matched : failed)++;
      // A view into the middle of both: rows are not continuous in memory.
      const cv::Rect inner(5, 3, 60, 41);
      expectSameComparison(compareImages(expected(inner), actual(inner), tolerance),
                           compareByLoop(expected(inner), actual(inner), tolerance), what + ", inner view");
    }
  }
  EXPECT_GT(matched, 0);
  EXPECT_GT(failed, 0);
}

TEST(ImageCompare, AgreesWithTheGoldenTestsVerdictOnAShiftedRender) {
  // The project's goldens are real llvmpipe renders; a render shifted by a pixel or two moves
  // every silhouette edge, the change the tolerance must tell from rounding.
  const fs::path goldens = fs::path(VDMAP_SOURCE_DIR) / "assets" / "golden";
  int cases = 0, matched = 0, failed = 0;
  for (const char* name : {"ellipsoids_global", "mesh", "mirror_scene", "container_view"}) {
    const cv::Mat bgr = test::readImage((goldens / (std::string(name) + ".png")));
    ASSERT_FALSE(bgr.empty()) << name;
    cv::Mat render;
    cv::cvtColor(bgr, render, cv::COLOR_BGR2RGB);
    for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{2, 2}, std::pair{6, 0}}) {
      const cv::Mat moved = shifted(render, dx, dy);
      const ImageComparison fast = compareImages(render, moved);
      const ImageComparison slow = compareByLoop(render, moved, ImageTolerance{});
      expectSameComparison(fast, slow,
                           std::string(name) + " shifted by " + std::to_string(dx) + "," + std::to_string(dy));
      ++cases;
      (fast.matches ? matched : failed)++;
    }
    EXPECT_TRUE(compareImages(render, render).matches);
  }
  EXPECT_EQ(cases, 16);
  EXPECT_GT(failed, 0) << "no shift of any golden changed the verdict";
  std::cout << matched << " of " << cases << " shifted goldens within the default tolerance\n";
}

// --- the nearby compare ----------------------------------------------------------------------

constexpr ImageTolerance kNearby{.channel_counts = 8, .pixel_share = 0, .method = CompareMethod::kNearby};

TEST(ImageCompareNearby, AOnePixelShiftAndScatteredSpecksDoNotDiffer) {
  // What another rasteriser does: silhouettes a pixel off, single pixels of the other colour.
  cv::Mat golden = uniform(40, 30, {20, 20, 30});
  cv::rectangle(golden, cv::Rect(10, 8, 15, 12), cv::Scalar(200, 120, 40), cv::FILLED);
  cv::Mat actual = shifted(golden, 1, 0);
  for (int k = 0; k < 6; ++k) actual.at<cv::Vec3b>(3 + 4 * k, 2 + 6 * k) = cv::Vec3b(255, 255, 255);
  EXPECT_GT(compareImages(golden, actual).differing, 12 + 6) << "the plain compare counts the edge and the specks";
  const ImageComparison c = compareImages(golden, actual, kNearby);
  EXPECT_EQ(c.differing, 0) << c.summary();
  EXPECT_TRUE(c.matches);
}

TEST(ImageCompareNearby, APatchOfAnotherColourDiffersWhole) {
  const cv::Mat golden = uniform(40, 30, {20, 20, 30});
  cv::Mat actual = golden.clone();
  actual(cv::Rect(5, 6, 4, 4)) = cv::Scalar(60, 20, 30);  // 40 counts off, 16 pixels
  const ImageComparison c = compareImages(golden, actual, kNearby);
  EXPECT_EQ(c.differing, 16) << c.summary();
  EXPECT_EQ(c.where, cv::Rect(5, 6, 4, 4));
  EXPECT_FALSE(c.matches);
  EXPECT_NE(c.summary().find("differ from everything within 1 px by more than 8 counts (nearby)"), std::string::npos)
      << c.summary();
  cv::Mat red;
  cv::inRange(diffImage(golden, actual, kNearby), cv::Scalar(255, 0, 0), cv::Scalar(255, 0, 0), red);
  EXPECT_EQ(cv::countNonZero(red), 16);
}

TEST(ImageCompareNearby, BusyTextureAllowsMoreThanAFlatSurface) {
  // The same 20-count change of a 3x3 patch: counted on a flat surface, not on a checkerboard of
  // 100 counts' contrast (a quarter of it, 25, plus 8 counts are allowed there).
  cv::Mat flat = uniform(20, 20, {100, 100, 100}), busy = flat.clone();
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x)
      if ((x + y) % 2) busy.at<cv::Vec3b>(y, x) = cv::Vec3b(200, 200, 200);
  const auto changed = [](const cv::Mat& golden) {
    cv::Mat actual = golden.clone();
    actual(cv::Rect(8, 8, 3, 3)) += cv::Scalar::all(20);
    return compareImages(golden, actual, kNearby).differing;
  };
  EXPECT_EQ(changed(flat), 9);
  EXPECT_EQ(changed(busy), 0);
}

// The nearby compare's oracle, one pixel at a time: a pixel of `image` finds no match when every
// pixel of `reference` within 1 px (the border repeated) is further than counts plus a quarter
// of the reference's local contrast (its 3x3's largest channel range, inside the image).
bool noMatchNear(const cv::Mat& reference, const cv::Mat& image, int x, int y, int counts) {
  int best = 255, contrast = 0;
  for (int c = 0; c < 3; ++c) {
    int lo = 255, hi = 0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int qx = x + dx, qy = y + dy;
        if (qx < 0 || qy < 0 || qx >= image.cols || qy >= image.rows) continue;
        lo = std::min(lo, int(reference.at<cv::Vec3b>(qy, qx)[c]));
        hi = std::max(hi, int(reference.at<cv::Vec3b>(qy, qx)[c]));
      }
    contrast = std::max(contrast, hi - lo);
  }
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int qx = std::clamp(x + dx, 0, image.cols - 1), qy = std::clamp(y + dy, 0, image.rows - 1);
      int d = 0;
      for (int c = 0; c < 3; ++c)
        d = std::max(d, std::abs(int(reference.at<cv::Vec3b>(qy, qx)[c]) - int(image.at<cv::Vec3b>(y, x)[c])));
      best = std::min(best, d);
    }
  const int allowed = std::min(255, static_cast<int>(std::nearbyint(0.25 * contrast + counts)));
  return best > allowed;
}

long nearbyDifferingByLoop(const cv::Mat& expected, const cv::Mat& actual, int counts) {
  cv::Mat differs(expected.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < expected.rows; ++y)
    for (int x = 0; x < expected.cols; ++x)
      differs.at<uchar>(y, x) =
          noMatchNear(expected, actual, x, y, counts) || noMatchNear(actual, expected, x, y, counts);
  long n = 0;
  for (int y = 0; y < expected.rows; ++y)
    for (int x = 0; x < expected.cols; ++x) {
      int around = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int qx = x + dx, qy = y + dy;
          around += qx >= 0 && qy >= 0 && qx < expected.cols && qy < expected.rows && differs.at<uchar>(qy, qx);
        }
      n += differs.at<uchar>(y, x) && around >= 3;
    }
  return n;
}

TEST(ImageCompareNearby, MatchesThePerPixelLoopOnRandomImages) {
  cv::RNG rng(7);
  long total = 0;
  for (int round = 0; round < 20; ++round) {
    // Blocks of colour (structure) with noise, and a copy shifted, recoloured and speckled in parts.
    cv::Mat expected(24 + round, 31, CV_8UC3);
    rng.fill(expected, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(256));
    cv::resize(expected(cv::Rect(0, 0, 8, 6)), expected, expected.size(), 0, 0, cv::INTER_NEAREST);
    cv::Mat noise(expected.size(), CV_8UC3);
    rng.fill(noise, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(12));
    expected += noise;
    cv::Mat actual = expected.clone();
    cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, round % 3 - 1, 0, 1, round % 2);
    cv::warpAffine(expected, actual, shift, expected.size(), cv::INTER_NEAREST, cv::BORDER_REPLICATE);
    actual(cv::Rect(round % 20, round % 15, 6, 5)) += cv::Scalar(round * 7 % 60, 30, 0);
    for (int k = 0; k < 15; ++k)
      actual.at<cv::Vec3b>(rng.uniform(0, actual.rows), rng.uniform(0, actual.cols)) = cv::Vec3b(255, 0, 255);
    const int counts = round % 4 * 4;
    const ImageTolerance nearby{counts, 0.01, CompareMethod::kNearby};
    const long by_loop = nearbyDifferingByLoop(expected, actual, counts);
    EXPECT_EQ(compareImages(expected, actual, nearby).differing, by_loop) << "round " << round;
    total += by_loop;
  }
  EXPECT_GT(total, 100) << "the images differ somewhere, so the two counts are compared on something";
}

TEST(ImageCompareNearby, MethodNamesRoundTrip) {
  for (const CompareMethod m : {CompareMethod::kPlain, CompareMethod::kNearby})
    EXPECT_EQ(parseCompareMethod(compareMethodName(m)), m);
  EXPECT_THROW(parseCompareMethod("fuzzy"), std::invalid_argument);
}

}  // namespace
}  // namespace vdmap::render
