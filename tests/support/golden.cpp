#include "tests/support/golden.h"

#include <filesystem>

#include <opencv2/imgproc.hpp>

#include "render/framebuffer.h"
#include "tests/support/test_util.h"

namespace vdmap::test {

namespace fs = std::filesystem;

::testing::AssertionResult matchesGolden(const cv::Mat& rgb, const std::string& name) {
  const fs::path golden = fs::path(VDMAP_SOURCE_DIR) / "assets" / "golden" / (name + ".png");
  const fs::path out_dir = fs::path(VDMAP_GOLDEN_OUT);
  fs::create_directories(out_dir);
  const cv::Mat expected_bgr = test::readImage(golden);
  if (expected_bgr.empty()) {
    const fs::path candidate = out_dir / (name + ".png");
    render::writePng(candidate, rgb);
    return ::testing::AssertionFailure() << "no golden " << golden << "; wrote the candidate " << candidate
                                         << " (inspect it, then copy it there)";
  }
  if (expected_bgr.size() != rgb.size())
    return ::testing::AssertionFailure() << "golden " << golden << " is " << expected_bgr.cols << "x"
                                         << expected_bgr.rows << ", the image " << rgb.cols << "x" << rgb.rows;
  cv::Mat expected;
  cv::cvtColor(expected_bgr, expected, cv::COLOR_BGR2RGB);
  const render::ImageComparison comparison = render::compareImages(expected, rgb, kGoldenTolerance);
  if (comparison.matches) return ::testing::AssertionSuccess();
  const fs::path actual = out_dir / (name + ".actual.png"), diff = out_dir / (name + ".diff.png");
  render::writePng(actual, rgb);
  render::writePng(diff, render::diffImage(expected, rgb, kGoldenTolerance));
  return ::testing::AssertionFailure() << name << ": " << comparison.summary() << "; wrote " << actual << " and "
                                       << diff;
}

}  // namespace vdmap::test
