#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"

namespace vdmap {

/// One decoded RGB-D frame with its pose.
struct FrameFeatures;  // mapping/keyframe/frame_features.h

struct RgbdFrame {
  int index = -1;          ///< position in the sequence's depth list (what --frames counts)
  double timestamp = 0.0;  ///< depth timestamp, seconds
  cv::Mat rgb;             ///< CV_8UC3, RGB channel order, camera size
  cv::Mat depth;           ///< CV_16UC1, raw units: metres = value / camera.depth_scale
  Transform T_W_C = Transform::Identity();
  /// The encoded files rgb and depth were decoded from, when read from files (empty otherwise):
  /// a new keyframe keeps these bytes instead of compressing the pixels again.
  std::shared_ptr<const std::string> rgb_file, depth_file;
  /// rgb was resampled from its file (colour registered to depth, colour_registration.h): a new
  /// keyframe keeps it as a JPEG (quality 95; a lossless PNG of these pixels would be several
  /// times the size, docs/notes/performance.md).
  bool rgb_resampled = false;
  /// The frame's ORB features computed ahead, on the prefetch thread, by the function
  /// Mapper::featuresAhead() gave (for that Mapper, `features_for`); otherwise null and
  /// addFrame() extracts them itself. Either way they are the same features.
  std::shared_ptr<const FrameFeatures> features;
  const void* features_for = nullptr;
  double features_ms = 0;  ///< how long computing them took (wall, on the prefetch thread)
};

/// A coloured point cloud; points and colours are parallel arrays.
struct ColoredPointCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<std::uint8_t, 3>> colors;
  std::size_t size() const { return points.size(); }
};

/// Back-projects every pixel whose depth lies in `range` into the camera frame (points_C).
ColoredPointCloud toPointCloud(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range = {});

}  // namespace vdmap
