#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>

namespace vdmap {

/// An image held compressed, decoded on demand (decode() gives back the pixels exactly, unless a
/// JPEG was asked for) by the sequence decoders (image_codec.h). The bytes held are a PNG or
/// JPEG file: either the file the image was read from (a sequence's JPEG or PNG, as it came) or,
/// for pixels from elsewhere, one this class wrote (a PNG, a fraction of the raw pixels; sizes in
/// docs/notes/performance.md). A session stores those bytes as they are (docs/vdmap-format.md).
/// Copies share the bytes. Immutable; safe to read from any thread.
class CompressedImage {
 public:
  CompressedImage() = default;
  /// CV_8UC3 or CV_16UC1 (channels kept in their order), or empty. `jpeg_quality` 1..100 keeps a
  /// colour image as a JPEG of that quality instead (lossy: decode() gives the JPEG's pixels),
  /// for pixels that were resampled from a JPEG anyway; 0: lossless PNG.
  explicit CompressedImage(const cv::Mat& image, int jpeg_quality = 0);
  /// Holds `file`, the encoded bytes `image` was decoded from by readColorImage (CV_8UC3) or
  /// readDepthImage (CV_16UC1); `image` only gives the size and type. Null `file`: as above.
  CompressedImage(const cv::Mat& image, std::shared_ptr<const std::string> file);
  /// Holds `bytes` as they are: a PNG or JPEG file of a rows x cols image of `type` (CV_8UC3 or
  /// CV_16UC1), whose red and blue channels are exchanged when `swapped_red_blue` (as encoded()
  /// and swappedRedBlue() of another image gave them). Not checked here: decode() throws
  /// InputError when they do not decode to that image.
  static CompressedImage fromEncoded(int rows, int cols, int type, std::string bytes, bool swapped_red_blue);

  /// The pixels (a new matrix each call); empty for an empty image. Throws InputError when the
  /// bytes held do not decode to the image's size and type (only possible through fromEncoded).
  cv::Mat decode() const;
  /// decode() naming `name` in its error.
  cv::Mat decode(const std::string& name) const;
  bool empty() const { return rows_ == 0 || cols_ == 0; }
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int type() const { return type_; }
  /// The PNG or JPEG file held ("" for an empty image).
  std::string_view encoded() const { return bytes_ ? std::string_view(*bytes_) : std::string_view(); }
  /// True when the file's red channel holds the image's blue and its blue the red: the pixel
  /// constructor hands a colour image to OpenCV's encoder, which takes BGR.
  bool swappedRedBlue() const { return swapped_red_blue_; }
  /// Bytes held (the file).
  std::size_t compressedBytes() const { return bytes_ ? bytes_->size() : 0; }

 private:
  int rows_ = 0, cols_ = 0, type_ = CV_8UC1;  // an empty image keeps the type it was given
  std::shared_ptr<const std::string> bytes_;
  bool swapped_red_blue_ = false;
};

}  // namespace vdmap
