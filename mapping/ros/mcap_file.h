#pragma once
// A ROS 2 recording in the MCAP format (https://mcap.dev/spec), read by our own reader: records,
// chunks (uncompressed, lz4 frames, zstd), CRCs, the summary section with its chunk indexes and
// statistics. Messages of "cdr" channels decode with messages.h as Encoding::kCdr, of "ros1"
// channels (an MCAP converted from a ROS 1 bag) as Encoding::kRos1; channels in any other
// encoding are listed with kind kOther.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "mapping/ros/recording.h"

namespace vdmap::ros {

namespace detail {
struct McapIndex;
struct McapBuffer;
}  // namespace detail

/// An MCAP file opened for reading. When the file has a summary that passes its CRC and indexes
/// every chunk, opening reads only the header, the footer and the summary. Without one (a
/// recording cut short, a writer that leaves it out) or when it is damaged, opening reads the
/// file once from the start, decompressing each chunk to find the channels, and ends its index at
/// the first damage, which every scan then reports after the messages before it.
/// Thread-safe: const methods may run concurrently.
///
/// MessageRef: `position` is the file offset of the chunk record holding the message and `offset`
/// the offset of the message record in the chunk's decompressed records; for a message outside any
/// chunk, `position` is the message record's own file offset and `offset` is 0.
class McapFile : public Recording {
 public:
  /// Opens `file` and reads its index. Throws InputError ("FILE: what is wrong") when it cannot be
  /// opened, is not MCAP (bad magic) or its header record is unreadable. Damage past the header
  /// does not throw: scans report it.
  static std::unique_ptr<McapFile> open(const std::filesystem::path& file);
  ~McapFile() override;
  McapFile(const McapFile&) = delete;
  McapFile& operator=(const McapFile&) = delete;

  /// "MCAP (profile ros2, zstd chunks, with summary)".
  std::string describe() const override;
  const std::filesystem::path& path() const override { return path_; }
  const std::vector<Topic>& topics() const override;
  /// See Recording::scan. Holds the decompressed chunks whose messages are next in log time: one
  /// chunk at a time when chunks do not overlap in time, more only while they overlap. Chunks
  /// holding none of the chosen topics (by the summary's chunk indexes) are not read.
  ScanEnd scan(const std::vector<int>& topics, const std::function<bool(const Message&)>& visit) const override;
  /// See Recording::read. Keeps the last decompressed chunk (under a mutex).
  Message read(const MessageRef& ref) const override;

  /// The largest chunk (compressed or decompressed) or single record vdmap reads: a larger declared
  /// size is damage, so a hostile file cannot make the reader allocate gigabytes. rosbag2 writes
  /// 4 MiB chunks; a chunk only grows past that to hold one large message (a point cloud of some
  /// tens of MB).
  static constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{512} << 20;

 private:
  McapFile(std::filesystem::path path, int fd, std::uint64_t size_bytes);

  std::filesystem::path path_;
  int fd_ = -1;  ///< read with pread only (no shared file position), so reads need no lock
  std::uint64_t size_bytes_ = 0;
  std::unique_ptr<const detail::McapIndex> index_;  ///< topics, channels, chunks; fixed after open()

  mutable std::mutex read_mutex_;  ///< guards the cache of read()
  mutable std::uint64_t cached_position_ = 0;
  mutable std::shared_ptr<const detail::McapBuffer> cached_chunk_;
};

}  // namespace vdmap::ros
