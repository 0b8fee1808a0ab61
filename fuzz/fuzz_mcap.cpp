// The MCAP reader and the CDR decoders: open, scan every topic, decode each message by its type,
// and read it again by its ref, which must give the same bytes. Seeds written without CRCs (a CRC
// of 0 means "not computed") let mutations reach the record parsers; with CRCs, nearly every
// mutation stops at the check.
#include <cstdlib>
#include <stdexcept>

#include "fuzz/fuzz_input.h"
#include "mapping/core/error.h"
#include "mapping/ros/detail/decoders.h"
#include "mapping/ros/mcap_file.h"

namespace {

/// Decodes `message` as its topic's type; a decoder's std::runtime_error is an expected outcome.
void decode(const vdmap::ros::Message& message, vdmap::ros::MessageType type) {
  using namespace vdmap::ros;
  if (message.encoding != Encoding::kCdr) return;  // the ROS 1 decoders are fuzzed with the bag reader
  const std::vector<std::uint8_t>& bytes = *message.bytes;
  try {
    switch (type) {
      case MessageType::kImage: detail::decodeImageCdr(bytes); break;
      case MessageType::kCompressedImage: detail::decodeCompressedImageCdr(bytes); break;
      case MessageType::kCameraInfo: detail::decodeCameraInfoCdr(bytes); break;
      case MessageType::kTfMessage:
      case MessageType::kTransform:
      case MessageType::kTransformStamped: detail::decodeTransformsCdr(bytes, type); break;
      case MessageType::kPoseStamped:
      case MessageType::kOdometry: detail::decodePoseCdr(bytes, type); break;
      case MessageType::kFloat32: detail::decodeFloat32Cdr(bytes); break;
      case MessageType::kOther: break;
    }
  } catch (const std::runtime_error&) {
  }
}

void scanAndDecode(const std::filesystem::path& file) {
  using namespace vdmap::ros;
  const auto mcap = McapFile::open(file);
  mcap->describe();
  std::vector<int> topics(mcap->topics().size());
  for (std::size_t i = 0; i < topics.size(); ++i) topics[i] = static_cast<int>(i);
  mcap->scan(topics, [&](const Message& message) {
    decode(message, mcap->topics()[static_cast<std::size_t>(message.topic)].kind);
    // A ref a scan gave must read back as the same message (an InputError here is a bug).
    try {
      const Message again = mcap->read(message.ref);
      if (again.topic != message.topic || again.log_time_ns != message.log_time_ns || *again.bytes != *message.bytes)
        std::abort();
    } catch (const vdmap::InputError&) {
      std::abort();
    }
    return true;
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = vdmap::fuzz::writeInput(data, size, "recording.mcap");
  VDMAP_FUZZ_EXPECTED_ERRORS(scanAndDecode(file));
  return 0;
}
