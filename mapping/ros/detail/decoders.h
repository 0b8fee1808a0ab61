#pragma once
// Each encoding's decoders; messages.cpp picks one by Encoding. ROS 1: ros1_messages.cpp (Debian's
// roscpp_serialization with the message headers). CDR: cdr_messages.cpp (our own; the 4-byte
// encapsulation header, then fields aligned to their size from the end of that header).
// Same contract as messages.h: std::runtime_error with a short reason on bytes that do not hold
// the type, never a read past the end.
#include "mapping/ros/messages.h"

namespace vdmap::ros::detail {

// head_only: the fields before the data (messages.h, decodeImageHead).
Image decodeImageRos1(const std::vector<std::uint8_t>& bytes, bool head_only = false);
CompressedImage decodeCompressedImageRos1(const std::vector<std::uint8_t>& bytes, bool head_only = false);
Image decodeImageRos1(std::vector<std::uint8_t>&&, bool = false) = delete;  // the image's data views the bytes
CompressedImage decodeCompressedImageRos1(std::vector<std::uint8_t>&&, bool = false) = delete;
CameraInfo decodeCameraInfoRos1(const std::vector<std::uint8_t>& bytes);
std::vector<TransformStamped> decodeTransformsRos1(const std::vector<std::uint8_t>& bytes, MessageType type);
PoseStamped decodePoseRos1(const std::vector<std::uint8_t>& bytes, MessageType type);
float decodeFloat32Ros1(const std::vector<std::uint8_t>& bytes);

Image decodeImageCdr(const std::vector<std::uint8_t>& bytes, bool head_only = false);
CompressedImage decodeCompressedImageCdr(const std::vector<std::uint8_t>& bytes, bool head_only = false);
Image decodeImageCdr(std::vector<std::uint8_t>&&, bool = false) = delete;  // the image's data views the bytes
CompressedImage decodeCompressedImageCdr(std::vector<std::uint8_t>&&, bool = false) = delete;
CameraInfo decodeCameraInfoCdr(const std::vector<std::uint8_t>& bytes);
std::vector<TransformStamped> decodeTransformsCdr(const std::vector<std::uint8_t>& bytes, MessageType type);
PoseStamped decodePoseCdr(const std::vector<std::uint8_t>& bytes, MessageType type);
float decodeFloat32Cdr(const std::vector<std::uint8_t>& bytes);

}  // namespace vdmap::ros::detail
