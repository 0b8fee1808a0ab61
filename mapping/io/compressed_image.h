#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace vdmap {

/// An image held compressed, decoded on demand (decode() gives back the pixels exactly, unless a
/// JPEG was asked for): either
/// the encoded file it was read from (a sequence's JPEG or PNG, decoded by the same decoder that
/// read it: 7-Scenes keeps ~0.13 MB per keyframe) or, for pixels from elsewhere, PNG-compressed
/// (~1/3 of the raw 1.5 MB at 640x480). Copies share the bytes. Immutable; safe to read from
/// any thread.
class CompressedImage {
 public:
  CompressedImage() = default;
  /// CV_8UC1, CV_8UC3 or CV_16UC1 (channels kept in their order), or empty. `jpeg_quality`
  /// 1..100 keeps an 8-bit image as a JPEG of that quality instead (lossy: decode() gives the
  /// JPEG's pixels), for pixels that were resampled from a JPEG anyway; 0: lossless PNG.
  explicit CompressedImage(const cv::Mat& image, int jpeg_quality = 0);
  /// Holds `file`, the encoded bytes `image` was decoded from by readColorImage (CV_8UC3) or
  /// readDepthImage (CV_16UC1); `image` only gives the size and type. Null `file`: as above.
  CompressedImage(const cv::Mat& image, std::shared_ptr<const std::string> file);

  /// The pixels (a new matrix each call); empty for an empty image.
  cv::Mat decode() const;
  bool empty() const { return rows_ == 0 || cols_ == 0; }
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int type() const { return type_; }
  /// Bytes held (the PNG stream or the file).
  std::size_t compressedBytes() const { return png_ ? png_->size() : file_ ? file_->size() : 0; }

 private:
  int rows_ = 0, cols_ = 0, type_ = CV_8UC1;
  std::shared_ptr<const std::vector<std::uint8_t>> png_;
  std::shared_ptr<const std::string> file_;
};

}  // namespace vdmap
