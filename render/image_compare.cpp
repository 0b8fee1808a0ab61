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

// Every pixel's largest channel range over its 3x3 (the local contrast; CV_8UC1).
cv::Mat localContrast(const cv::Mat& image) {
  cv::Mat high, low, range;
  cv::dilate(image, high, cv::Mat());
  cv::erode(image, low, cv::Mat());
  cv::Mat channels[3];
  cv::split(high - low, channels);
  cv::max(channels[0], channels[1], range);
  cv::max(range, channels[2], range);
  return range;
}

// Where no pixel of `reference` within 1 px is within counts + a quarter of the reference's local
// contrast of `image`'s.
cv::Mat nothingNearMatches(const cv::Mat& reference, const cv::Mat& image, int counts) {
  cv::Mat padded, best(image.size(), CV_8UC1, cv::Scalar(255));
  cv::copyMakeBorder(reference, padded, 1, 1, 1, 1, cv::BORDER_REPLICATE);
  for (int dy = 0; dy <= 2; ++dy)
    for (int dx = 0; dx <= 2; ++dx)
      cv::min(best, largestChannelDifference(padded(cv::Rect(dx, dy, image.cols, image.rows)), image), best);
  cv::Mat allowed;
  localContrast(reference).convertTo(allowed, CV_8U, 0.25, counts);
  return best > allowed;
}

// The nearby compare's differing pixels (ImageTolerance says why): nothing near matches, either
// way, and at least 3 of the 3x3 differ so.
cv::Mat nearbyDiffering(const cv::Mat& expected, const cv::Mat& actual, int counts) {
  const cv::Mat differs = nothingNearMatches(expected, actual, counts) | nothingNearMatches(actual, expected, counts);
  cv::Mat neighbours;
  cv::boxFilter(differs / 255, neighbours, CV_8U, cv::Size(3, 3), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  return differs & (neighbours >= 3);
}

// The pixels the tolerance's method counts as differing (CV_8UC1, 255 where they do).
cv::Mat differingPixels(const cv::Mat& expected, const cv::Mat& actual, const cv::Mat& difference,
                        const ImageTolerance& tolerance) {
  if (tolerance.method == CompareMethod::kNearby) return nearbyDiffering(expected, actual, tolerance.channel_counts);
  return difference > tolerance.channel_counts;
}

long countAbove(const std::array<long, 256>& counts, int threshold) {
  long n = 0;
  for (int d = threshold + 1; d < 256; ++d) n += counts[d];
  return n;
}

}  // namespace

const char* compareMethodName(CompareMethod method) { return method == CompareMethod::kNearby ? "nearby" : "plain"; }

CompareMethod parseCompareMethod(const std::string& text) {
  if (text == "plain") return CompareMethod::kPlain;
  if (text == "nearby") return CompareMethod::kNearby;
  throw std::invalid_argument("'" + text + "': expected plain or nearby");
}

std::string ImageComparison::summary() const {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(3) << differing << " of " << pixels << " pixels (" << 100.0 * share << "%, allowed "
      << 100.0 * tolerance.pixel_share << "%) differ "
      << (tolerance.method == CompareMethod::kNearby ? "from everything within 1 px " : "") << "by more than "
      << tolerance.channel_counts << " counts" << (tolerance.method == CompareMethod::kNearby ? " (nearby)" : "")
      << "; " << over1 << " by more than 1, " << over32 << " by more than 32, worst " << worst;
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
  const cv::Mat differs = differingPixels(expected_rgb, actual_rgb, difference, tolerance);
  c.differing = cv::countNonZero(differs);
  c.over1 = countAbove(counts, 1);
  c.over32 = countAbove(counts, 32);
  for (int d = 255; d > 0 && c.worst == 0; --d)
    if (counts[d] > 0) c.worst = d;
  c.share = static_cast<double>(c.differing) / static_cast<double>(c.pixels);
  if (c.differing > 0) c.where = cv::boundingRect(differs);
  c.matches = c.share <= tolerance.pixel_share;
  return c;
}

cv::Mat diffImage(const cv::Mat& expected_rgb, const cv::Mat& actual_rgb, const ImageTolerance& tolerance) {
  requireComparable(expected_rgb, actual_rgb, tolerance);
  const cv::Mat differs =
      differingPixels(expected_rgb, actual_rgb, largestChannelDifference(expected_rgb, actual_rgb), tolerance);
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
