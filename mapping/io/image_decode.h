#pragma once
// Decoding of a sequence's colour and depth images (PNG, JPEG) with libpng and libjpeg directly,
// through their error and warning hooks: a damaged or truncated file is one InputError naming
// it, and the libraries never print to stderr. (OpenCV's imread let libjpeg print "Premature
// end of JPEG file", naming no file, and returned the grey-filled image as if it were whole.)
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

}  // namespace vdmap
