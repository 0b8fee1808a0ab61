#pragma once
// The ROS messages vdmap reads from recordings, as plain structs, and their decoders from either
// encoding: ROS 1 serialisation (bags; decoded through Debian's roscpp_serialization and the
// sensor_msgs/tf2_msgs/geometry_msgs/nav_msgs headers, ros1_messages.cpp) and ROS 2's CDR (MCAP,
// our own reader, cdr_messages.cpp). Field names follow the messages'; stamps are in seconds.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

namespace vdmap::ros {

enum class Encoding { kRos1, kCdr };

/// The message types vdmap understands (and the rest).
enum class MessageType {
  kImage,             ///< sensor_msgs/Image
  kCompressedImage,   ///< sensor_msgs/CompressedImage (colour JPEG/PNG, or compressedDepth)
  kCameraInfo,        ///< sensor_msgs/CameraInfo
  kTfMessage,         ///< tf2_msgs/TFMessage (and ROS 1's tf/tfMessage, the same layout)
  kTransform,         ///< geometry_msgs/Transform (RealSense's recorded stream extrinsics)
  kTransformStamped,  ///< geometry_msgs/TransformStamped
  kPoseStamped,       ///< geometry_msgs/PoseStamped
  kOdometry,          ///< nav_msgs/Odometry
  kFloat32,           ///< std_msgs/Float32 (RealSense's recorded options, e.g. Depth Units)
  kOther,
};

/// The type of a recorded type name: ROS 1's "sensor_msgs/Image" and ROS 2's
/// "sensor_msgs/msg/Image" alike; kOther for anything else.
MessageType messageType(std::string_view type_name);

struct Header {
  double stamp = 0.0;  ///< s (sec + nanosec * 1e-9)
  std::string frame_id;
};

struct Image {
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string encoding;  ///< "16UC1", "mono16", "32FC1", "rgb8", "bgr8", "rgba8", "bgra8", "mono8", ...
  bool is_bigendian = false;
  std::uint32_t step = 0;              ///< bytes per row
  std::span<const std::uint8_t> data;  ///< in the decoded message's bytes (valid while they are)
};

struct CompressedImage {
  Header header;
  std::string format;  ///< "jpeg", "png", "rgb8; jpeg compressed bgr8", "16UC1; compressedDepth png", ...
  std::span<const std::uint8_t> data;  ///< in the decoded message's bytes (valid while they are)
};

struct CameraInfo {
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};  ///< row-major 3x3 intrinsics
  std::array<double, 9> r{};
  std::array<double, 12> p{};  ///< row-major 3x4 projection
};

/// geometry_msgs/TransformStamped: the pose of child_frame_id in header.frame_id, i.e. it maps
/// points from the child frame to the parent frame. A bare geometry_msgs/Transform decodes to
/// this with an empty header and child.
struct TransformStamped {
  Header header;
  std::string child_frame_id;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< as recorded (not normalised)
};

/// A pose in header.frame_id: geometry_msgs/PoseStamped, or nav_msgs/Odometry's pose.pose (whose
/// child_frame_id is kept).
struct PoseStamped {
  Header header;
  std::string child_frame_id;  ///< Odometry only
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// Decoders. Each throws std::runtime_error with a short reason ("image data holds 100 bytes,
/// height * step needs 614400", "message ends inside field 'encoding'") when the bytes do not hold
/// a message of that type; callers add the file and the topic. Never read past `bytes`.
/// An image's data is a view into `bytes`, so they must outlive it (no temporaries).
Image decodeImage(const std::vector<std::uint8_t>& bytes, Encoding encoding);
CompressedImage decodeCompressedImage(const std::vector<std::uint8_t>& bytes, Encoding encoding);
Image decodeImage(std::vector<std::uint8_t>&&, Encoding) = delete;
CompressedImage decodeCompressedImage(std::vector<std::uint8_t>&&, Encoding) = delete;
/// The fields before an image's data (header, size, encoding; a CompressedImage's header and
/// format), from the message whole or its first bytes (Recording::scanHeads); data left empty.
Image decodeImageHead(const std::vector<std::uint8_t>& bytes, Encoding encoding);
CompressedImage decodeCompressedImageHead(const std::vector<std::uint8_t>& bytes, Encoding encoding);
CameraInfo decodeCameraInfo(const std::vector<std::uint8_t>& bytes, Encoding encoding);
/// tf2_msgs/TFMessage: its transforms; TransformStamped and Transform: one.
std::vector<TransformStamped> decodeTransforms(const std::vector<std::uint8_t>& bytes, Encoding encoding,
                                               MessageType type);
/// PoseStamped or Odometry.
PoseStamped decodePose(const std::vector<std::uint8_t>& bytes, Encoding encoding, MessageType type);
float decodeFloat32(const std::vector<std::uint8_t>& bytes, Encoding encoding);

}  // namespace vdmap::ros
