#pragma once
// What the recording fuzzers do with a file their reader opened: scan every topic, decode each
// message by its type (a decoder's std::runtime_error is an expected outcome), and read it again
// by its ref, which must give the same message (anything else, an InputError included, is a bug).
#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include "mapping/core/error.h"
#include "mapping/ros/recording.h"

namespace vdmap::fuzz {

inline void decodeAs(const std::vector<std::uint8_t>& bytes, ros::Encoding encoding, ros::MessageType type) {
  using ros::MessageType;
  try {
    switch (type) {
      case MessageType::kImage:
        ros::decodeImageHead(bytes, encoding);
        ros::decodeImage(bytes, encoding);
        break;
      case MessageType::kCompressedImage:
        ros::decodeCompressedImageHead(bytes, encoding);
        ros::decodeCompressedImage(bytes, encoding);
        break;
      case MessageType::kCameraInfo: ros::decodeCameraInfo(bytes, encoding); break;
      case MessageType::kTfMessage:
      case MessageType::kTransform:
      case MessageType::kTransformStamped: ros::decodeTransforms(bytes, encoding, type); break;
      case MessageType::kPoseStamped:
      case MessageType::kOdometry: ros::decodePose(bytes, encoding, type); break;
      case MessageType::kFloat32: ros::decodeFloat32(bytes, encoding); break;
      case MessageType::kOther: break;
    }
  } catch (const std::runtime_error&) {
  }
}

inline void scanEveryMessage(const ros::Recording& recording) {
  recording.describe();
  std::vector<int> topics(recording.topics().size());
  std::iota(topics.begin(), topics.end(), 0);
  recording.scan(topics, [&](const ros::Message& message) {
    decodeAs(*message.bytes, message.encoding, recording.topics().at(message.topic).kind);
    try {
      const ros::Message again = recording.read(message.ref);
      if (again.topic != message.topic || again.log_time_ns != message.log_time_ns || *again.bytes != *message.bytes)
        std::abort();
    } catch (const InputError&) {
      std::abort();
    }
    return true;
  });
  // Every topic's messages as heads: each is its message's first bytes, or all of them.
  recording.scanHeads(topics, topics, [&](const ros::Message& message) {
    try {
      const ros::Message whole = recording.read(message.ref);
      if (message.bytes->size() > whole.bytes->size() ||
          !std::equal(message.bytes->begin(), message.bytes->end(), whole.bytes->begin()) ||
          message.head_only != (message.bytes->size() < whole.bytes->size()))
        std::abort();
    } catch (const InputError&) {
      // A heads scan does not decompress what lies past the messages' heads: damage there shows
      // when the message is read whole, as an InputError.
    }
    return true;
  });
}

}  // namespace vdmap::fuzz
