#pragma once
// A robot's recording read message by message: a ROS 1 bag (ros1_bag.h, our own reader of bag
// format 2.0) or a ROS 2 MCAP file (mcap_file.h, our own reader of the published format).
// Both give the same topics, message references and decoded messages (messages.h), so what turns
// messages into RGB-D frames (mapping/sequence/) does not know which file it reads.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mapping/ros/messages.h"

namespace vdmap::ros {

/// One topic (an MCAP channel, a bag connection's topic) with the type of its messages.
struct Topic {
  std::string name;  ///< "/camera/depth/image"
  std::string type;  ///< as recorded: "sensor_msgs/Image" (ROS 1) or "sensor_msgs/msg/Image" (ROS 2)
  MessageType kind = MessageType::kOther;  ///< messageType(type)
  std::uint64_t count = 0;                 ///< messages on it (from the index; 0 when unknown)
};

/// Where a message lies in its file, to read it again with Recording::read(). Opaque to callers.
struct MessageRef {
  std::uint64_t position = 0;  ///< e.g. the chunk's file offset
  std::uint64_t offset = 0;    ///< e.g. the record's offset in the chunk's decompressed bytes
};

/// One message, undecoded. Decode it with the functions of messages.h.
struct Message {
  int topic = -1;                ///< index into Recording::topics()
  std::int64_t log_time_ns = 0;  ///< when the recorder received it (not the header stamp)
  MessageRef ref;
  Encoding encoding = Encoding::kRos1;
  std::shared_ptr<const std::vector<std::uint8_t>> bytes;  ///< the serialised message
  bool head_only = false;                                  ///< bytes hold only its first bytes (Recording::scanHeads)
};

/// How a scan ended: at the end of the file, or at damage (a truncated file, a bad CRC, a record
/// that does not parse), with one line saying where, e.g. "FILE: truncated at byte 123456 in a
/// chunk (messages after 12.345 s are lost)". Messages before the damage were visited.
struct ScanEnd {
  bool complete = true;
  std::string damage;  ///< empty when complete
};

/// A recording opened for reading. Opening reads the file's index (summary) when it has one;
/// it throws InputError ("FILE: what is wrong") when the file is not a recording of this kind at
/// all or cannot be read. const methods are safe to call from several threads.
class Recording {
 public:
  virtual ~Recording() = default;

  /// "ROS 1 bag (format 2.0, lz4 chunks)", "MCAP (profile ros2, zstd chunks, with summary)".
  virtual std::string describe() const = 0;
  virtual const std::filesystem::path& path() const = 0;
  virtual const std::vector<Topic>& topics() const = 0;

  /// Visits, in log-time order (ties in file order), every message on the given topics (indices
  /// into topics()); `visit` returns false to stop early. Reads the file once from the start,
  /// holding one chunk in memory (a few where chunks overlap in time). Damage ends the scan without throwing (see ScanEnd).
  virtual ScanEnd scan(const std::vector<int>& topics, const std::function<bool(const Message&)>& visit) const = 0;

  /// As scan(), but a message on a topic of `heads` (image topics) may come as its first bytes
  /// only (Message::head_only): enough for decodeImageHead(). Listing a recording's frames needs
  /// no more of its images. A reader that cannot cut them short gives them whole.
  virtual ScanEnd scanHeads(const std::vector<int>& topics, const std::vector<int>& heads,
                            const std::function<bool(const Message&)>& visit) const {
    (void)heads;
    return scan(topics, visit);
  }

  /// The message a scan gave with this ref. Throws InputError naming the file when it cannot be
  /// read. Reading refs in file order is cheap (the last chunk read is kept).
  virtual Message read(const MessageRef& ref) const = 0;
};

/// What the file is, by its first bytes: "#ROSBAG V2.0\n" or the MCAP magic "\x89MCAP0\r\n".
enum class RecordingFormat { kNone, kRos1Bag, kMcap };
RecordingFormat recordingFormat(const std::filesystem::path& file);

/// Opens a ROS 1 bag or an MCAP file, whichever it is. Throws InputError when it is neither.
std::unique_ptr<Recording> openRecording(const std::filesystem::path& file);

}  // namespace vdmap::ros
