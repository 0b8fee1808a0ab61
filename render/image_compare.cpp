#include "render/image_compare.h"

#include <array>
#include <iomanip>
#include <locale>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace vdmap::render {
namespace {

std::string sizeText(const cv::Mat& image) { return std::to_string(image.cols) + "x" + std::to_string(image.rows); }

void requireComparable(const cv::Mat& expected, const cv::Mat& actual, const ImageTolerance& tolerance) {
  if (expected.empty() || actual.empty()) throw std::invalid_argument("compareImages: an image is empty");
  if (expected.type() != CV_8UC3 || actual.type() != CV_8UC3)
    throw std::invalid_argument("compareImages: images must be 8-bit with three channels");
  if (expected.size() != actual.size())
    throw std::invalid_argument("the expected image is " + sizeText(expected) + ", the actual one " + sizeText(actual));
  if (tolerance.channel_counts < 0 || tolerance.channel_counts > 255 || !(tolerance.pixel_share >= 0) ||
      tolerance.pixel_share > 1)
    throw std::invalid_argument("compareImages: the tolerance must be 0..255 counts and a share in [0, 1]");
}

// Every pixel's largest absolute channel difference (CV_8UC1). OpenCV's vectorised absdiff, split
// and max: three passes over the image, fast enough for a suite of full-HD renders.
cv::Mat largestChannelDifference(const cv::Mat& expected, const cv::Mat& actual) {
  cv::Mat diff;
  cv::absdiff(expected, actual, diff);
  cv::Mat channels[3];
  cv::split(diff, channels);
  cv::Mat largest;
  cv::max(channels[0], channels[1], largest);
  cv::max(largest, channels[2], largest);
  return largest;
}

// How many pixels have each difference 0..255: every count the comparison reports is a tail sum.
std::array<long, 256> histogram(const cv::Mat& difference) {
  std::array<long, 256> counts{};
  for (int y = 0; y < difference.rows; ++y) {
    const uchar* row = difference.ptr<uchar>(y);
    for (int x = 0; x < difference.cols; ++x) ++counts[row[x]];
  }
  return counts;
}

long countAbove(const std::array<long, 256>& counts, int threshold) {
  long n = 0;
  for (int d = threshold + 1; d < 256; ++d) n += counts[d];
  return n;
}

}  // namespace

std::string ImageComparison::summary() const {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(3) << differing << " of " << pixels << " pixels (" << 100.0 * share << "%, allowed "
      << 100.0 * tolerance.pixel_share << "%) differ by more than " << tolerance.channel_counts << " counts; " << over1
      << " by more than 1, " << over32 << " by more than 32, worst " << worst;
  if (!where.empty())
    out << ", inside x " << where.x << ".." << where.x + where.width - 1 << " y " << where.y << ".."
        << where.y + where.height - 1;
  return out.str();
}

ImageComparison compareImages(const cv::Mat& expected_rgb, const cv::Mat& actual_rgb, const ImageTolerance& tolerance) {
  requireComparable(expected_rgb, actual_rgb, tolerance);
  const cv::Mat difference = largestChannelDifference(expected_rgb, actual_rgb);
  const std::array<long, 256> counts = histogram(difference);
  ImageComparison c;
  c.tolerance = tolerance;
  c.pixels = static_cast<long>(difference.total());
  c.differing = countAbove(counts, tolerance.channel_counts);
  c.over1 = countAbove(counts, 1);
  c.over32 = countAbove(counts, 32);
  for (int d = 255; d > 0 && c.worst == 0; --d)
    if (counts[d] > 0) c.worst = d;
  c.share = static_cast<double>(c.differing) / static_cast<double>(c.pixels);
  if (c.differing > 0) c.where = cv::boundingRect(difference > tolerance.channel_counts);
  c.matches = c.share <= tolerance.pixel_share;
  return c;
}

cv::Mat diffImage(const cv::Mat& expected_rgb, const cv::Mat& actual_rgb, const ImageTolerance& tolerance) {
  requireComparable(expected_rgb, actual_rgb, tolerance);
  const cv::Mat differs = largestChannelDifference(expected_rgb, actual_rgb) > tolerance.channel_counts;
  cv::Mat grey;
  cv::cvtColor(expected_rgb, grey, cv::COLOR_RGB2GRAY);
  grey.convertTo(grey, CV_8U, 0.5, 64.0);
  cv::Mat out;
  cv::cvtColor(grey, out, cv::COLOR_GRAY2RGB);
  out.setTo(cv::Scalar(255, 0, 0), differs);
  if (cv::countNonZero(differs) > 0) {
    const cv::Rect where = cv::boundingRect(differs);
    // Just outside the box, so that no red pixel is hidden; cv::rectangle clips to the image.
    cv::rectangle(out, cv::Point(where.x - 1, where.y - 1), cv::Point(where.x + where.width, where.y + where.height),
                  cv::Scalar(255, 255, 0), 1, cv::LINE_8);
  }
  return out;
}

}  // namespace vdmap::render
