// The ROS 1 bag reader and decoders: open, scan every topic, decode each message by its type, and
// read it again by its ref, which must give the same bytes.
#include "fuzz/fuzz_input.h"
#include "mapping/core/error.h"
#include "mapping/ros/detail/decoders.h"
#include "mapping/ros/ros1_bag.h"

namespace {

using namespace vdmap::ros;

/// Decodes `bytes` as `type`; the decoders' documented error is std::runtime_error.
void decode(const std::vector<std::uint8_t>& bytes, MessageType type) {
  try {
    switch (type) {
      case MessageType::kImage: detail::decodeImageRos1(bytes); break;
      case MessageType::kCompressedImage: detail::decodeCompressedImageRos1(bytes); break;
      case MessageType::kCameraInfo: detail::decodeCameraInfoRos1(bytes); break;
      case MessageType::kTfMessage:
      case MessageType::kTransform:
      case MessageType::kTransformStamped: detail::decodeTransformsRos1(bytes, type); break;
      case MessageType::kPoseStamped:
      case MessageType::kOdometry: detail::decodePoseRos1(bytes, type); break;
      case MessageType::kFloat32: detail::decodeFloat32Ros1(bytes); break;
      case MessageType::kOther: break;
    }
  } catch (const std::runtime_error&) {
  }
}

void readBag(const std::filesystem::path& file) {
  const auto bag = Ros1Bag::open(file);
  std::vector<int> topics(bag->topics().size());
  for (std::size_t i = 0; i < topics.size(); ++i) topics[i] = static_cast<int>(i);
  bag->describe();
  bag->scan(topics, [&](const Message& m) {
    decode(*m.bytes, bag->topics().at(m.topic).kind);
    // Every message a scan gave is there to read again.
    if (*bag->read(m.ref).bytes != *m.bytes) __builtin_trap();
    return true;
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = vdmap::fuzz::writeInput(data, size, "recording.bag");
  VDMAP_FUZZ_EXPECTED_ERRORS(readBag(file));
  // The same bytes as each message type.
  const std::vector<std::uint8_t> bytes(data, data + size);
  for (int type = 0; type < static_cast<int>(MessageType::kOther); ++type)
    decode(bytes, static_cast<MessageType>(type));
  return 0;
}
