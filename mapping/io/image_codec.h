#pragma once
// PNG and JPEG images, read and written with libpng and libjpeg directly. Decoding goes through
// their error and warning hooks: a damaged or truncated file is one InputError naming it, and
// the libraries never print to stderr. (OpenCV's imread let libjpeg print "Premature end of JPEG
// file", naming no file, and returned the grey-filled image as if it were whole.) Encoding gives
// the bytes OpenCV's imencode gives for the same settings (tests hold them to it), without
// loading OpenCV's image codecs, whose dependencies (GDAL, GDCM, ...) cost every process that
// links them a noticeable delay at start.
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

namespace vdmap {

/// Decodes a PNG or JPEG colour image of size `expected` into CV_8UC3 in RGB order (grey and
/// palette images are expanded, alpha dropped, 16-bit channels reduced to their high byte).
/// Throws InputError "FILE: cannot decode colour image: WHAT" for an unreadable, damaged,
/// truncated or non-PNG/JPEG file (a JPEG warning, such as a premature end or corrupt data,
/// counts as damage) and "FILE: colour image is WxH but the camera is WxH" for another size,
/// found from the header before any pixel is allocated.
/// `file_bytes`, when given, receives the file's encoded bytes (a keyframe keeps them instead of
/// compressing the pixels again).
cv::Mat readColorImage(const std::filesystem::path& file, cv::Size expected, std::string* file_bytes = nullptr);

/// Decodes a 16-bit single-channel PNG depth image of size `expected` into CV_16UC1 (raw units).
/// Throws InputError as readColorImage ("cannot decode depth image: ...", "depth image is ...")
/// and "FILE: depth image must be 16-bit single-channel, got N-bit C-channel" for any other
/// layout.
cv::Mat readDepthImage(const std::filesystem::path& file, cv::Size expected, std::string* file_bytes = nullptr);

/// The same decoders on bytes already in memory (what readColorImage / readDepthImage read from
/// `name`): the pixels are exactly those the file gave.
cv::Mat decodeColorImage(const std::string& bytes, cv::Size expected, const std::string& name);
cv::Mat decodeDepthImage(const std::string& bytes, cv::Size expected, const std::string& name);
/// The same decoders at whatever size the file has.
cv::Mat decodeColorImage(const std::string& bytes, const std::string& name);
cv::Mat decodeDepthImage(const std::string& bytes, const std::string& name);

/// Which channel of a 3-channel matrix is the file's red: kRgb (channel 0) or kBgr (channel 2,
/// as OpenCV's imencode takes it).
enum class ChannelOrder { kRgb, kBgr };

/// How a PNG is compressed. kFast: the sub filter, zlib level 1 and run-length strategy (what
/// imencode does without parameters); kLevel1: libpng's filter choice, zlib level 1 and the
/// default strategy (imencode with IMWRITE_PNG_COMPRESSION 1). Both are lossless.
enum class PngCompression { kFast, kLevel1 };

/// The PNG file of `image`: CV_8UC1 (grey), CV_8UC3 (colour, channels in `order`) or CV_16UC1.
std::string encodePng(const cv::Mat& image, ChannelOrder order = ChannelOrder::kRgb,
                      PngCompression compression = PngCompression::kFast);

/// The baseline JPEG file of a CV_8UC3 `image` (channels in `order`) at `quality` 1..100, with
/// libjpeg's defaults otherwise (4:2:0 chroma, JFIF header), as imencode writes it.
std::string encodeJpeg(const cv::Mat& image, int quality, ChannelOrder order = ChannelOrder::kRgb);

/// encodePng or encodeJpeg (quality 95) by the extension of `file` (.png, .jpg, .jpeg; any case),
/// written to `file` directly (not atomically: for many frames of a sequence). Throws
/// InputError naming the file for another extension or when it cannot be written.
void writeImageFile(const std::filesystem::path& file, const cv::Mat& image, ChannelOrder order = ChannelOrder::kRgb);

}  // namespace vdmap
