#include "mapping/ros/messages.h"

#include <stdexcept>

#include "mapping/ros/detail/decoders.h"

namespace vdmap::ros {

MessageType messageType(std::string_view name) {
  // ROS 2 names put "msg/" between the package and the type.
  std::string type(name);
  if (const auto slash = type.find("/msg/"); slash != std::string::npos) type.erase(slash, 4);
  if (type == "sensor_msgs/Image") return MessageType::kImage;
  if (type == "sensor_msgs/CompressedImage") return MessageType::kCompressedImage;
  if (type == "sensor_msgs/CameraInfo") return MessageType::kCameraInfo;
  if (type == "tf2_msgs/TFMessage" || type == "tf/tfMessage") return MessageType::kTfMessage;
  if (type == "geometry_msgs/Transform") return MessageType::kTransform;
  if (type == "geometry_msgs/TransformStamped") return MessageType::kTransformStamped;
  if (type == "geometry_msgs/PoseStamped") return MessageType::kPoseStamped;
  if (type == "nav_msgs/Odometry") return MessageType::kOdometry;
  if (type == "std_msgs/Float32") return MessageType::kFloat32;
  return MessageType::kOther;
}

Image decodeImage(const std::vector<std::uint8_t>& bytes, Encoding encoding) {
  return encoding == Encoding::kRos1 ? detail::decodeImageRos1(bytes) : detail::decodeImageCdr(bytes);
}

CompressedImage decodeCompressedImage(const std::vector<std::uint8_t>& bytes, Encoding encoding) {
  return encoding == Encoding::kRos1 ? detail::decodeCompressedImageRos1(bytes)
                                     : detail::decodeCompressedImageCdr(bytes);
}

Image decodeImageHead(const std::vector<std::uint8_t>& bytes, Encoding encoding) {
  return encoding == Encoding::kRos1 ? detail::decodeImageRos1(bytes, true) : detail::decodeImageCdr(bytes, true);
}

CompressedImage decodeCompressedImageHead(const std::vector<std::uint8_t>& bytes, Encoding encoding) {
  return encoding == Encoding::kRos1 ? detail::decodeCompressedImageRos1(bytes, true)
                                     : detail::decodeCompressedImageCdr(bytes, true);
}

CameraInfo decodeCameraInfo(const std::vector<std::uint8_t>& bytes, Encoding encoding) {
  return encoding == Encoding::kRos1 ? detail::decodeCameraInfoRos1(bytes) : detail::decodeCameraInfoCdr(bytes);
}

std::vector<TransformStamped> decodeTransforms(const std::vector<std::uint8_t>& bytes, Encoding encoding,
                                               MessageType type) {
  return encoding == Encoding::kRos1 ? detail::decodeTransformsRos1(bytes, type)
                                     : detail::decodeTransformsCdr(bytes, type);
}

PoseStamped decodePose(const std::vector<std::uint8_t>& bytes, Encoding encoding, MessageType type) {
  return encoding == Encoding::kRos1 ? detail::decodePoseRos1(bytes, type) : detail::decodePoseCdr(bytes, type);
}

float decodeFloat32(const std::vector<std::uint8_t>& bytes, Encoding encoding) {
  return encoding == Encoding::kRos1 ? detail::decodeFloat32Ros1(bytes) : detail::decodeFloat32Cdr(bytes);
}

}  // namespace vdmap::ros
