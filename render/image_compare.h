#pragma once
// Comparison of a rendered image with a reference ("golden") image: the one metric of the
// project's golden tests and of users' screenshot regression tests. Pure CPU (OpenCV); no GL.
#include <string>

#include <opencv2/core.hpp>

namespace vdmap::render {

/// When two images count as the same picture. A pixel differs when any channel differs by more
/// than `channel_counts`; the images match when at most `pixel_share` of the pixels differ.
/// Why the defaults: llvmpipe is deterministic on one machine, but another Mesa version or CPU
/// (AVX2 vs SSE4 code paths) rounds shading by a count or two and may move a silhouette edge by
/// one pixel. 8 counts is well above shading rounding and well below any real change of colour
/// mode or lighting; 0.5 % of the pixels is about one pixel along every edge of a small scene
/// (384 px of a 320x240 image), while a wrong camera, sigma or colour moves thousands of pixels.
///
/// `nearby` tells a driver from a change. Another rasteriser (Mesa's softpipe for llvmpipe) picks
/// the other of two overlapping ellipsoids where they meet and moves silhouettes by a pixel:
/// scattered single pixels, up to 255 counts off, over 3-8 % of a dense map's pixels. A real
/// change (a parameter, a turned camera) moves whole patches. So with `nearby` a pixel differs
/// only when no pixel within 1 px in the other image matches it (both ways), where "matches"
/// allows `channel_counts` plus a quarter of the local contrast (the largest channel range of
/// the 3x3 around the pixel: busy texture and seams allow more than flat surfaces), and only
/// when at least 3 pixels of its 3x3 differ so (a patch, not a speck).
enum class CompareMethod { kPlain, kNearby };
struct ImageTolerance {
  int channel_counts = 8;      ///< in [0, 255]
  double pixel_share = 0.005;  ///< in [0, 1]
  CompareMethod method = CompareMethod::kPlain;
};

/// "plain" or "nearby", and back (std::invalid_argument naming both).
const char* compareMethodName(CompareMethod method);
CompareMethod parseCompareMethod(const std::string& text);

/// How two images of the same size differ. Counts are of pixels; a pixel's difference is the
/// largest absolute difference of its three channels.
struct ImageComparison {
  long pixels = 0;      ///< width x height
  long differing = 0;   ///< pixels differing by more than tolerance.channel_counts (nearby: as it says)
  long over1 = 0;       ///< pixels differing by more than 1 count
  long over32 = 0;      ///< pixels differing by more than 32 counts
  int worst = 0;        ///< the largest difference, in counts (0: identical)
  double share = 0;     ///< differing / pixels
  cv::Rect where;       ///< bounding box of the differing pixels (empty when none differ)
  bool matches = true;  ///< share <= tolerance.pixel_share
  ImageTolerance tolerance;

  /// One line: "1532 of 76800 pixels (2%, allowed 0.5%) differ by more than 8 counts; 2011 by
  /// more than 1, 310 by more than 32, worst 187, inside x 12..240 y 30..199" (no "inside" when
  /// no pixel differs). The nearby compare says "differ from everything within 1 px by more
  /// than 8 counts (nearby)".
  std::string summary() const;
};

/// Compares `actual` with `expected`, both CV_8UC3 in RGB order (any channel order works as long
/// as both share it). Throws std::invalid_argument for empty images, another type, a tolerance
/// out of range, or images of different sizes ("the expected image is 320x240, the actual one
/// 160x120").
ImageComparison compareImages(const cv::Mat& expected_rgb, const cv::Mat& actual_rgb,
                              const ImageTolerance& tolerance = {});

/// An RGB picture of where two images differ: `expected` in grey at half contrast
/// (64 + luma / 2), the pixels that differ beyond `tolerance` in red (255, 0, 0), and a 1 px
/// yellow (255, 255, 0) box just outside their bounding box (clipped to the image; none when no
/// pixel differs). Throws as compareImages.
cv::Mat diffImage(const cv::Mat& expected_rgb, const cv::Mat& actual_rgb, const ImageTolerance& tolerance = {});

}  // namespace vdmap::render
