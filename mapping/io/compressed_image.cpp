#include "mapping/io/compressed_image.h"

#include <cassert>
#include <opencv2/imgproc.hpp>

#include "mapping/io/image_codec.h"

namespace vdmap {

// PNG at zlib level 1: the higher levels take longer on every keyframe and make the files only
// slightly smaller. Depth with the sub filter and run-length strategy (kFast), which encodes a
// 7-Scenes depth image in about half the time of libpng's filter choice at the same size;
// colour with libpng's choice (docs/notes/performance.md has the figures).
CompressedImage::CompressedImage(const cv::Mat& image, int jpeg_quality)
    : rows_(image.rows), cols_(image.cols), type_(image.type()) {
  if (image.empty()) return;
  assert(type_ == CV_8UC3 || type_ == CV_16UC1);
  assert(jpeg_quality >= 0 && jpeg_quality <= 100 && (jpeg_quality == 0 || type_ != CV_16UC1));
  // The file holds the image's blue as its red (swapped_red_blue_), which decode() undoes: so
  // keyframes have been written since OpenCV's encoder (which takes BGR) wrote them, and a
  // JPEG's pixels stay those it has always given.
  bytes_ = std::make_shared<const std::string>(
      jpeg_quality > 0
          ? encodeJpeg(image, jpeg_quality, ChannelOrder::kBgr)
          : encodePng(image, ChannelOrder::kBgr, type_ == CV_16UC1 ? PngCompression::kFast : PngCompression::kLevel1));
  swapped_red_blue_ = type_ == CV_8UC3;
}

CompressedImage::CompressedImage(const cv::Mat& image, std::shared_ptr<const std::string> file)
    : CompressedImage(file ? cv::Mat() : image) {
  if (!file) return;
  assert(image.type() == CV_8UC3 || image.type() == CV_16UC1);
  rows_ = image.rows, cols_ = image.cols, type_ = image.type();
  bytes_ = std::move(file);
}

CompressedImage CompressedImage::fromEncoded(int rows, int cols, int type, std::string bytes, bool swapped_red_blue) {
  CompressedImage out;
  out.rows_ = rows, out.cols_ = cols, out.type_ = type;
  if (out.empty()) return out;
  assert(type == CV_8UC3 || type == CV_16UC1);
  out.bytes_ = std::make_shared<const std::string>(std::move(bytes));
  out.swapped_red_blue_ = swapped_red_blue && type == CV_8UC3;
  return out;
}

cv::Mat CompressedImage::decode() const {
  return decode(type_ == CV_16UC1 ? "a keyframe's depth file" : "a keyframe's colour file");
}

cv::Mat CompressedImage::decode(const std::string& name) const {
  if (!bytes_) return cv::Mat(rows_, cols_, type_);
  const cv::Size size(cols_, rows_);
  if (type_ == CV_16UC1) return decodeDepthImage(*bytes_, size, name);
  cv::Mat out = decodeColorImage(*bytes_, size, name);
  if (swapped_red_blue_) cv::cvtColor(out, out, cv::COLOR_RGB2BGR);
  return out;
}

}  // namespace vdmap
