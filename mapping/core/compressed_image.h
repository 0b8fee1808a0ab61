#pragma once
#include <cstddef>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

namespace vdmap {

/// An image held PNG-compressed (lossless: decode() gives back the pixels exactly), decoded on
/// demand, so a keyframe's colour and depth images cost ~1/3 of their raw size while resident.
/// Copies share the bytes. Immutable; safe to read from any thread.
class CompressedImage {
 public:
  CompressedImage() = default;
  /// CV_8UC1, CV_8UC3 or CV_16UC1 (channels kept in their order), or empty.
  explicit CompressedImage(const cv::Mat& image);

  /// The pixels (a new matrix each call); empty for an empty image.
  cv::Mat decode() const;
  bool empty() const { return rows_ == 0 || cols_ == 0; }
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int type() const { return type_; }
  /// Bytes held (the PNG stream).
  std::size_t compressedBytes() const { return png_ ? png_->size() : 0; }

 private:
  int rows_ = 0, cols_ = 0, type_ = CV_8UC1;
  std::shared_ptr<const std::vector<std::uint8_t>> png_;
};

}  // namespace vdmap
