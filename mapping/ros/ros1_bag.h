#pragma once
// A ROS 1 bag (format 2.0, http://wiki.ros.org/Bags/Format/2.0) read as a Recording.
//
// Read by our own small reader, not rosbag_storage: rosbag_storage trusts every length and offset
// in the file (it allocates the header lengths it reads, reads chunk buffers at index offsets
// unchecked, and loads the encryptor plugin a bag names), so a damaged or hostile bag can crash
// it, and it refuses a bag whose index is missing. Here every length is checked against the file
// and the chunk before it is used; what rosbag_storage read of the shared bags (once, by a small
// rosbag::View program) is the tests' oracle. Chunks are decompressed with liblz4's frame API (rosbag's lz4 chunks are LZ4 frames)
// and libbz2. ROS headers stay out of this file: the implementation is behind a pimpl.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "mapping/ros/recording.h"

namespace vdmap::ros {

/// A ROS 1 bag. Opening reads its index (the connection and chunk records at its end and the index
/// records after each chunk). A bag without a usable index (a recorder that did not close it, a
/// truncated file) is read once from the start at open to rebuild one, keeping the messages before
/// the damage: then scan() ends with a damage note such as "FILE: truncated at byte N (the bag's
/// index is missing); messages after T s are lost". MessageRef is {chunk's file offset, record's
/// offset in the decompressed chunk}. const methods are thread-safe.
class Ros1Bag : public Recording {
 public:
  /// Throws InputError when `file` cannot be read or is not a ROS 1 bag of format 2.0 (or is one
  /// this reader cannot read: an encrypted bag).
  static std::unique_ptr<Ros1Bag> open(const std::filesystem::path& file);
  ~Ros1Bag() override;

  std::string describe() const override;
  const std::filesystem::path& path() const override;
  const std::vector<Topic>& topics() const override;
  ScanEnd scan(const std::vector<int>& topics, const std::function<bool(const Message&)>& visit) const override;
  /// Decompresses each chunk only as far as the messages asked for: a heads message costs its
  /// first kilobyte and what lies before it in its chunk. Damage beyond what was asked for is
  /// not seen (read() sees it).
  ScanEnd scanHeads(const std::vector<int>& topics, const std::vector<int>& heads,
                    const std::function<bool(const Message&)>& visit) const override;
  Message read(const MessageRef& ref) const override;

 private:
  struct Impl;
  explicit Ros1Bag(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vdmap::ros
