// ROS 2 messages in CDR (XCDR1, as rmw implementations write it): a 4-byte encapsulation header
// (0x00 0x01: little endian; 0x00 0x00: big endian; then two option bytes), then the fields in
// order, each primitive aligned to its own size counted from the byte after that header; a string
// is a uint32 length counting its NUL, then the bytes and the NUL; a sequence is a uint32 count,
// then its elements; fixed arrays have no count. builtin_interfaces/Time is int32 sec + uint32
// nanosec; ROS 2's std_msgs/Header is stamp + frame_id (no seq).
#include <cstring>
#include <stdexcept>
#include <string>

#include "mapping/ros/detail/decoders.h"

namespace vdmap::ros::detail {

// File-scope names carry "Cdr": the target is compiled in unity batches (CMakeLists.txt), where
// they must not meet the ROS 1 decoders' in this namespace.
namespace {

constexpr std::size_t kCdrEncapsulationBytes = 4;

/// Reads CDR fields in order, never past the end: every read names its field, which the error
/// gives ("message ends inside field 'encoding'").
class CdrReader {
 public:
  explicit CdrReader(const std::vector<std::uint8_t>& bytes) : data_(bytes.data()), size_(bytes.size()) {
    if (size_ < kCdrEncapsulationBytes)
      throw std::runtime_error("message of " + std::to_string(size_) +
                               " bytes ends inside the CDR encapsulation header");
    // Byte 1's low bit is the endianness for every encapsulation kind; only plain CDR (kinds 0
    // and 1) has the layout read here. XCDR2 (kinds 6 to 11) aligns 8-byte values to 4 and adds
    // headers; parameter lists (2, 3) tag each field.
    if (data_[0] != 0 || data_[1] > 1)
      throw std::runtime_error("CDR encapsulation 0x" + hex(data_[0]) + hex(data_[1]) +
                               " is not plain CDR (0x0000 big or 0x0001 little endian)");
    big_endian_ = data_[1] == 0;
    pos_ = kCdrEncapsulationBytes;
  }

  std::uint8_t u8(const char* field) { return static_cast<std::uint8_t>(primitive(1, field)); }
  std::uint32_t u32(const char* field) { return static_cast<std::uint32_t>(primitive(4, field)); }
  std::int32_t i32(const char* field) { return static_cast<std::int32_t>(u32(field)); }
  float f32(const char* field) {
    const std::uint32_t bits = u32(field);
    float value;
    std::memcpy(&value, &bits, sizeof(value));
    return value;
  }
  double f64(const char* field) {
    const std::uint64_t bits = primitive(8, field);
    double value;
    std::memcpy(&value, &bits, sizeof(value));
    return value;
  }
  bool boolean(const char* field) { return u8(field) != 0; }

  std::string string(const char* field) {
    const std::uint32_t length = u32(field);
    const std::uint8_t* bytes = take(length, field);
    // The length counts the terminating NUL; some writers give 0 for an empty string.
    std::size_t chars = length;
    if (chars > 0 && bytes[chars - 1] == 0) --chars;
    return std::string(reinterpret_cast<const char*>(bytes), chars);
  }

  /// A sequence's element count, checked against the bytes left (each element takes at least
  /// `min_element_bytes`) so a bad count cannot make the caller allocate.
  std::uint32_t count(const char* field, std::size_t min_element_bytes) {
    const std::uint32_t n = u32(field);
    if (static_cast<std::uint64_t>(n) * min_element_bytes > size_ - pos_)
      throw std::runtime_error("message ends inside field '" + std::string(field) + "' (" + std::to_string(n) +
                               " elements declared, " + std::to_string(size_ - pos_) + " bytes left)");
    return n;
  }

  std::span<const std::uint8_t> byteSequence(const char* field) {
    const std::uint32_t n = count(field, 1);
    return {take(n, field), n};
  }

  std::vector<double> doubleSequence(const char* field) {
    const std::uint32_t n = count(field, 8);
    std::vector<double> values(n);
    for (double& value : values) value = f64(field);
    return values;
  }

  template <std::size_t N>
  void doubles(std::array<double, N>* values, const char* field) {
    for (double& value : *values) value = f64(field);
  }

 private:
  static std::string hex(std::uint8_t byte) {
    constexpr char kDigits[] = "0123456789abcdef";
    return {kDigits[byte >> 4], kDigits[byte & 15]};
  }

  const std::uint8_t* take(std::size_t n, const char* field) {
    if (n > size_ - pos_) throw std::runtime_error("message ends inside field '" + std::string(field) + "'");
    const std::uint8_t* at = data_ + pos_;
    pos_ += n;
    return at;
  }

  /// A `bytes`-wide unsigned value, aligned to its size from the end of the encapsulation header.
  std::uint64_t primitive(std::size_t bytes, const char* field) {
    const std::size_t misaligned = (pos_ - kCdrEncapsulationBytes) % bytes;
    if (misaligned != 0) take(bytes - misaligned, field);
    const std::uint8_t* at = take(bytes, field);
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < bytes; ++i) value = (value << 8) | at[big_endian_ ? i : bytes - 1 - i];
    return value;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  bool big_endian_ = false;
};

// Smallest serialised sizes, to bound sequence counts before allocating: a TransformStamped is at
// least a stamp (8), two empty strings (4 + 4) and seven doubles (56).
constexpr std::size_t kCdrMinTransformStampedBytes = 8 + 4 + 4 + 7 * 8;

Header readCdrHeader(CdrReader& cdr) {
  Header header;
  const std::int32_t sec = cdr.i32("header.stamp.sec");
  const std::uint32_t nanosec = cdr.u32("header.stamp.nanosec");
  header.stamp = static_cast<double>(sec) + static_cast<double>(nanosec) * 1e-9;
  header.frame_id = cdr.string("header.frame_id");
  return header;
}

Eigen::Vector3d readCdrVector3(CdrReader& cdr, const char* field) {
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = cdr.f64(field);
  return v;
}

Eigen::Quaterniond readCdrQuaternion(CdrReader& cdr, const char* field) {
  const double x = cdr.f64(field), y = cdr.f64(field), z = cdr.f64(field), w = cdr.f64(field);
  return Eigen::Quaterniond(w, x, y, z);
}

void readCdrTransform(CdrReader& cdr, TransformStamped* transform) {
  transform->translation = readCdrVector3(cdr, "transform.translation");
  transform->rotation = readCdrQuaternion(cdr, "transform.rotation");
}

TransformStamped readCdrTransformStamped(CdrReader& cdr) {
  TransformStamped transform;
  transform.header = readCdrHeader(cdr);
  transform.child_frame_id = cdr.string("child_frame_id");
  readCdrTransform(cdr, &transform);
  return transform;
}

}  // namespace

Image decodeImageCdr(const std::vector<std::uint8_t>& bytes, bool head_only) {
  CdrReader cdr(bytes);
  Image image;
  image.header = readCdrHeader(cdr);
  image.height = cdr.u32("height");
  image.width = cdr.u32("width");
  image.encoding = cdr.string("encoding");
  image.is_bigendian = cdr.u8("is_bigendian") != 0;
  image.step = cdr.u32("step");
  if (head_only) return image;
  image.data = cdr.byteSequence("data");
  const std::uint64_t needed = static_cast<std::uint64_t>(image.height) * image.step;
  if (image.data.size() < needed)
    throw std::runtime_error("image data holds " + std::to_string(image.data.size()) + " bytes, height * step needs " +
                             std::to_string(needed));
  return image;
}

CompressedImage decodeCompressedImageCdr(const std::vector<std::uint8_t>& bytes, bool head_only) {
  CdrReader cdr(bytes);
  CompressedImage image;
  image.header = readCdrHeader(cdr);
  image.format = cdr.string("format");
  if (head_only) return image;
  image.data = cdr.byteSequence("data");
  return image;
}

CameraInfo decodeCameraInfoCdr(const std::vector<std::uint8_t>& bytes) {
  CdrReader cdr(bytes);
  CameraInfo info;
  info.header = readCdrHeader(cdr);
  info.height = cdr.u32("height");
  info.width = cdr.u32("width");
  info.distortion_model = cdr.string("distortion_model");
  info.d = cdr.doubleSequence("d");
  cdr.doubles(&info.k, "k");
  cdr.doubles(&info.r, "r");
  cdr.doubles(&info.p, "p");
  // Not kept, but read: a message cut short there is damaged all the same.
  cdr.u32("binning_x");
  cdr.u32("binning_y");
  cdr.u32("roi.x_offset");
  cdr.u32("roi.y_offset");
  cdr.u32("roi.height");
  cdr.u32("roi.width");
  cdr.boolean("roi.do_rectify");
  return info;
}

std::vector<TransformStamped> decodeTransformsCdr(const std::vector<std::uint8_t>& bytes, MessageType type) {
  CdrReader cdr(bytes);
  std::vector<TransformStamped> transforms;
  switch (type) {
    case MessageType::kTfMessage: {
      const std::uint32_t n = cdr.count("transforms", kCdrMinTransformStampedBytes);
      transforms.reserve(n);
      for (std::uint32_t i = 0; i < n; ++i) transforms.push_back(readCdrTransformStamped(cdr));
      break;
    }
    case MessageType::kTransformStamped: transforms.push_back(readCdrTransformStamped(cdr)); break;
    case MessageType::kTransform: {
      TransformStamped transform;
      readCdrTransform(cdr, &transform);
      transforms.push_back(transform);
      break;
    }
    default: throw std::runtime_error("not a transform message type");
  }
  return transforms;
}

PoseStamped decodePoseCdr(const std::vector<std::uint8_t>& bytes, MessageType type) {
  if (type != MessageType::kPoseStamped && type != MessageType::kOdometry)
    throw std::runtime_error("not a pose message type");
  CdrReader cdr(bytes);
  PoseStamped pose;
  pose.header = readCdrHeader(cdr);
  if (type == MessageType::kOdometry) pose.child_frame_id = cdr.string("child_frame_id");
  pose.position = readCdrVector3(cdr, "pose.position");
  pose.orientation = readCdrQuaternion(cdr, "pose.orientation");
  if (type == MessageType::kOdometry) {
    // Covariances and the twist are not kept, but a message cut short inside them is damaged.
    for (int i = 0; i < 36; ++i) cdr.f64("pose.covariance");
    for (int i = 0; i < 6; ++i) cdr.f64("twist.twist");
    for (int i = 0; i < 36; ++i) cdr.f64("twist.covariance");
  }
  return pose;
}

float decodeFloat32Cdr(const std::vector<std::uint8_t>& bytes) {
  CdrReader cdr(bytes);
  return cdr.f32("data");
}

}  // namespace vdmap::ros::detail
