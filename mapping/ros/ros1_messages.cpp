// The ROS 1 decoders of detail/decoders.h, through Debian's roscpp_serialization and the message
// headers. Each message is read field by field, as its generated serializer would, so that an
// overrun names the field. ros::serialization resizes a vector to the length the bytes claim
// before checking that the bytes hold it; a garbage length would ask for gigabytes, so each
// vector's length is checked against the bytes left first.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/serialization.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float32.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "mapping/ros/detail/decoders.h"

namespace vdmap::ros::detail {
namespace {

namespace rs = ::ros::serialization;

// The generated message structs and ros::serialization name allocators through
// ContainerAllocator::rebind, which C++20's std::allocator no longer has: this one gives it back.
template <typename T>
struct Ros1Allocator : std::allocator<T> {
  Ros1Allocator() = default;
  template <typename U>
  Ros1Allocator(const Ros1Allocator<U>&) noexcept {}
  template <typename U>
  struct rebind {
    using other = Ros1Allocator<U>;
  };
};
using A = Ros1Allocator<void>;
using Ros1Header = std_msgs::Header_<A>;

/// Reads one message's fields in order from its serialised bytes.
class Ros1Fields {
 public:
  // IStream only reads; it takes a non-const pointer for its writing twin's sake.
  explicit Ros1Fields(const std::vector<std::uint8_t>& bytes)
      : stream_(const_cast<std::uint8_t*>(bytes.data()), checkedSize(bytes)) {}

  /// The next field, named in the error when the bytes end inside it.
  template <typename T>
  void next(const char* name, T& value) {
    try {
      stream_.next(value);
    } catch (const rs::StreamOverrunException&) {
      throw std::runtime_error(std::string("message ends inside field '") + name + "'");
    }
  }

  /// The next uint8[] field into `out`, copied once (a ROS vector would be copied again into ours).
  void nextBytes(const char* name, std::span<const std::uint8_t>& out) {
    std::uint32_t length = 0;
    next(name, length);
    if (length > stream_.getLength()) throw std::runtime_error(std::string("message ends inside field '") + name + "'");
    out = {stream_.advance(length), length};
  }

  /// The next variable-length array, whose elements take at least `min_element_bytes` each: its
  /// length is checked against the bytes left before ros::serialization allocates it.
  template <typename Vector>
  void nextArray(const char* name, Vector& value, std::uint32_t min_element_bytes) {
    std::uint32_t length = 0;
    const std::uint32_t left = stream_.getLength();
    if (left >= 4) std::memcpy(&length, stream_.getData(), 4);
    if (left >= 4 && std::uint64_t{length} * min_element_bytes > left - 4)
      throw std::runtime_error(std::string("field '") + name + "' claims " + std::to_string(length) +
                               " elements, the message holds " + std::to_string(left - 4) + " bytes more");
    next(name, value);
  }

 private:
  static std::uint32_t checkedSize(const std::vector<std::uint8_t>& bytes) {
    // Every message decoded here has fields; and IStream would do arithmetic on a null pointer.
    if (bytes.empty()) throw std::runtime_error("empty message");
    if (bytes.size() > UINT32_MAX) throw std::runtime_error("a message of more than 4 GiB");
    return static_cast<std::uint32_t>(bytes.size());
  }

  rs::IStream stream_;
};

template <typename Text>
std::string text(const Text& t) {
  return std::string(t.data(), t.size());
}

Header header(const Ros1Header& h) { return {h.stamp.sec + h.stamp.nsec * 1e-9, text(h.frame_id)}; }

Eigen::Vector3d vector(const geometry_msgs::Vector3_<A>& v) { return {v.x, v.y, v.z}; }
Eigen::Vector3d vector(const geometry_msgs::Point_<A>& p) { return {p.x, p.y, p.z}; }
Eigen::Quaterniond quaternion(const geometry_msgs::Quaternion_<A>& q) { return {q.w, q.x, q.y, q.z}; }

TransformStamped transform(const geometry_msgs::TransformStamped_<A>& t) {
  return {header(t.header), text(t.child_frame_id), vector(t.transform.translation), quaternion(t.transform.rotation)};
}

// A serialised geometry_msgs/TransformStamped: header (seq, stamp, frame_id's length), child_frame_id's
// length, translation and rotation.
constexpr std::uint32_t kMinTransformStampedBytes = 4 + 8 + 4 + 4 + 7 * 8;

}  // namespace

Image decodeImageRos1(const std::vector<std::uint8_t>& bytes, bool head_only) {
  sensor_msgs::Image_<A> m;
  Ros1Fields fields(bytes);
  fields.next("header", m.header);
  fields.next("height", m.height);
  fields.next("width", m.width);
  fields.next("encoding", m.encoding);
  fields.next("is_bigendian", m.is_bigendian);
  fields.next("step", m.step);
  Image image{header(m.header), m.height, m.width, text(m.encoding), m.is_bigendian != 0, m.step, {}};
  if (head_only) return image;
  fields.nextBytes("data", image.data);
  if (image.data.size() < std::uint64_t{m.height} * m.step)
    throw std::runtime_error("image data holds " + std::to_string(image.data.size()) + " bytes, height * step needs " +
                             std::to_string(std::uint64_t{m.height} * m.step));
  return image;
}

CompressedImage decodeCompressedImageRos1(const std::vector<std::uint8_t>& bytes, bool head_only) {
  sensor_msgs::CompressedImage_<A> m;
  Ros1Fields fields(bytes);
  fields.next("header", m.header);
  fields.next("format", m.format);
  CompressedImage image{header(m.header), text(m.format), {}};
  if (head_only) return image;
  fields.nextBytes("data", image.data);
  return image;
}

CameraInfo decodeCameraInfoRos1(const std::vector<std::uint8_t>& bytes) {
  sensor_msgs::CameraInfo_<A> m;
  Ros1Fields fields(bytes);
  fields.next("header", m.header);
  fields.next("height", m.height);
  fields.next("width", m.width);
  fields.next("distortion_model", m.distortion_model);
  fields.nextArray("D", m.D, sizeof(double));
  fields.next("K", m.K);
  fields.next("R", m.R);
  fields.next("P", m.P);
  fields.next("binning_x", m.binning_x);
  fields.next("binning_y", m.binning_y);
  fields.next("roi", m.roi);
  CameraInfo info{header(m.header), m.height, m.width, text(m.distortion_model), {m.D.begin(), m.D.end()}};
  std::copy(m.K.begin(), m.K.end(), info.k.begin());
  std::copy(m.R.begin(), m.R.end(), info.r.begin());
  std::copy(m.P.begin(), m.P.end(), info.p.begin());
  return info;
}

std::vector<TransformStamped> decodeTransformsRos1(const std::vector<std::uint8_t>& bytes, MessageType type) {
  Ros1Fields fields(bytes);
  switch (type) {
    case MessageType::kTfMessage: {
      tf2_msgs::TFMessage_<A> m;
      fields.nextArray("transforms", m.transforms, kMinTransformStampedBytes);
      std::vector<TransformStamped> out;
      out.reserve(m.transforms.size());
      for (const auto& t : m.transforms) out.push_back(transform(t));
      return out;
    }
    case MessageType::kTransformStamped: {
      geometry_msgs::TransformStamped_<A> m;
      fields.next("header", m.header);
      fields.next("child_frame_id", m.child_frame_id);
      fields.next("transform", m.transform);
      return {transform(m)};
    }
    case MessageType::kTransform: {
      geometry_msgs::Transform_<A> m;
      fields.next("translation", m.translation);
      fields.next("rotation", m.rotation);
      return {TransformStamped{{}, {}, vector(m.translation), quaternion(m.rotation)}};
    }
    default: throw std::runtime_error("not a transform message type");
  }
}

PoseStamped decodePoseRos1(const std::vector<std::uint8_t>& bytes, MessageType type) {
  Ros1Fields fields(bytes);
  switch (type) {
    case MessageType::kPoseStamped: {
      geometry_msgs::PoseStamped_<A> m;
      fields.next("header", m.header);
      fields.next("pose", m.pose);
      return {header(m.header), {}, vector(m.pose.position), quaternion(m.pose.orientation)};
    }
    case MessageType::kOdometry: {
      // The twist is read too, though unused: bytes that end before it are not an Odometry.
      nav_msgs::Odometry_<A> m;
      fields.next("header", m.header);
      fields.next("child_frame_id", m.child_frame_id);
      fields.next("pose", m.pose);
      fields.next("twist", m.twist);
      return {header(m.header), text(m.child_frame_id), vector(m.pose.pose.position),
              quaternion(m.pose.pose.orientation)};
    }
    default: throw std::runtime_error("not a pose message type");
  }
}

float decodeFloat32Ros1(const std::vector<std::uint8_t>& bytes) {
  std_msgs::Float32_<A> m;
  Ros1Fields fields(bytes);
  fields.next("data", m.data);
  return m.data;
}

}  // namespace vdmap::ros::detail
