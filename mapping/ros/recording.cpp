#include "mapping/ros/recording.h"

#include <cstring>
#include <fstream>

#include "mapping/core/error.h"
#include "mapping/ros/mcap_file.h"
#include "mapping/ros/ros1_bag.h"

namespace vdmap::ros {

RecordingFormat recordingFormat(const std::filesystem::path& file) {
  static constexpr char kBag[] = "#ROSBAG V2.0\n";
  static constexpr char kMcap[] = "\x89MCAP0\r\n";
  char head[16] = {};
  std::ifstream in(file, std::ios::binary);
  in.read(head, sizeof head);
  const auto got = static_cast<std::size_t>(in.gcount());
  if (got >= sizeof kBag - 1 && std::memcmp(head, kBag, sizeof kBag - 1) == 0) return RecordingFormat::kRos1Bag;
  if (got >= sizeof kMcap - 1 && std::memcmp(head, kMcap, sizeof kMcap - 1) == 0) return RecordingFormat::kMcap;
  return RecordingFormat::kNone;
}

std::unique_ptr<Recording> openRecording(const std::filesystem::path& file) {
  switch (recordingFormat(file)) {
    case RecordingFormat::kRos1Bag: return Ros1Bag::open(file);
    case RecordingFormat::kMcap: return McapFile::open(file);
    default: throw InputError(file.string(), "is neither a ROS 1 bag (#ROSBAG V2.0) nor an MCAP file");
  }
}

}  // namespace vdmap::ros
