#include "tests/golden.h"

#include <filesystem>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace vdmap::test {

namespace fs = std::filesystem;

::testing::AssertionResult matchesGolden(const cv::Mat& rgb, const std::string& name) {
  const fs::path golden = fs::path(VDMAP_SOURCE_DIR) / "assets" / "golden" / (name + ".png");
  const fs::path out_dir = fs::path(VDMAP_GOLDEN_OUT);
  fs::create_directories(out_dir);
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  const cv::Mat expected = cv::imread(golden.string(), cv::IMREAD_COLOR);
  if (expected.empty()) {
    const fs::path candidate = out_dir / (name + ".png");
    cv::imwrite(candidate.string(), bgr);
    return ::testing::AssertionFailure() << "no golden " << golden << "; wrote the candidate "
                                         << candidate << " (inspect it, then copy it there)";
  }
  if (expected.size() != bgr.size())
    return ::testing::AssertionFailure() << "golden " << golden << " is " << expected.cols << "x"
                                         << expected.rows << ", the image " << bgr.cols << "x" << bgr.rows;
  cv::Mat absdiff;
  cv::absdiff(expected, bgr, absdiff);
  std::vector<cv::Mat> channels;
  cv::split(absdiff, channels);
  cv::Mat maxdiff = cv::max(cv::max(channels[0], channels[1]), channels[2]);
  double worst = 0;
  cv::minMaxLoc(maxdiff, nullptr, &worst);
  const int over1 = cv::countNonZero(maxdiff > 1), over8 = cv::countNonZero(maxdiff > kGoldenChannelTolerance),
            over32 = cv::countNonZero(maxdiff > 32);
  const double fraction = static_cast<double>(over8) / maxdiff.total();
  if (fraction <= kGoldenPixelFraction) return ::testing::AssertionSuccess();
  const cv::Rect where = cv::boundingRect(maxdiff > kGoldenChannelTolerance);
  const fs::path actual = out_dir / (name + ".actual.png"), diff = out_dir / (name + ".diff.png");
  cv::imwrite(actual.string(), bgr);
  cv::Mat diff_image;
  cv::normalize(maxdiff, diff_image, 0, 255, cv::NORM_MINMAX);
  cv::imwrite(diff.string(), diff_image);
  return ::testing::AssertionFailure()
         << name << ": " << over8 << " pixels (" << 100.0 * fraction << "%, allowed "
         << 100.0 * kGoldenPixelFraction << "%) differ by more than " << kGoldenChannelTolerance
         << " counts; " << over1 << " by more than 1, " << over32 << " by more than 32, worst "
         << worst << ", inside x " << where.x << ".." << where.x + where.width - 1 << " y " << where.y
         << ".." << where.y + where.height - 1 << "; wrote " << actual << " and " << diff;
}

}  // namespace vdmap::test
