#include "mapping/io/compressed_image.h"

#include <cassert>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "mapping/io/image_decode.h"

namespace vdmap {

// PNG level 1 (zlib's fastest): on 7-Scenes keyframes it is ~4 ms for colour and depth
// together, and the higher levels save only a few percent more.
CompressedImage::CompressedImage(const cv::Mat& image, int jpeg_quality)
    : rows_(image.rows), cols_(image.cols), type_(image.type()) {
  if (image.empty()) return;
  assert(type_ == CV_8UC1 || type_ == CV_8UC3 || type_ == CV_16UC1);
  assert(jpeg_quality >= 0 && jpeg_quality <= 100 && (jpeg_quality == 0 || type_ != CV_16UC1));
  // imencode takes 3 channels as BGR and imdecode returns them as BGR: the order round-trips.
  std::vector<std::uint8_t> png;
  const bool jpeg = jpeg_quality > 0;
  if (!cv::imencode(jpeg ? ".jpg" : ".png", image, png,
                    {jpeg ? cv::IMWRITE_JPEG_QUALITY : cv::IMWRITE_PNG_COMPRESSION, jpeg ? jpeg_quality : 1}))
    throw std::runtime_error("encoding of a keyframe image failed");
  png.shrink_to_fit();
  png_ = std::make_shared<const std::vector<std::uint8_t>>(std::move(png));
}

CompressedImage::CompressedImage(const cv::Mat& image, std::shared_ptr<const std::string> file)
    : CompressedImage(file ? cv::Mat() : image) {
  if (!file) return;
  assert(image.type() == CV_8UC3 || image.type() == CV_16UC1);
  rows_ = image.rows, cols_ = image.cols, type_ = image.type();
  file_ = std::move(file);
}

cv::Mat CompressedImage::decode() const {
  if (file_) {
    const cv::Size size(cols_, rows_);
    return type_ == CV_16UC1 ? decodeDepthImage(*file_, size, "a keyframe's depth file")
                             : decodeColorImage(*file_, size, "a keyframe's colour file");
  }
  if (!png_) return cv::Mat(rows_, cols_, type_);
  cv::Mat out = cv::imdecode(*png_, cv::IMREAD_UNCHANGED);
  if (out.rows != rows_ || out.cols != cols_ || out.type() != type_)
    throw std::runtime_error("a keyframe image did not decode to its own size and type");
  return out;
}

}  // namespace vdmap
