#pragma once
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "mapping/sequence/sequence.h"

namespace vdmap {

/// Decodes the frames of a sequence in order on a background thread, at most `capacity` ahead
/// of the consumer, so decoding overlaps mapping and memory stays bounded. One consumer thread.
class FramePrefetcher {
 public:
  /// Work done on the prefetch thread to each frame after decoding it (e.g. the Mapper's
  /// featuresAhead(): its ORB extraction then overlaps the previous frame's mapping).
  using Prepare = std::function<void(RgbdFrame&)>;

  /// `sequence` must outlive the prefetcher.
  explicit FramePrefetcher(const Sequence& sequence, std::size_t capacity = 4, Prepare prepare = {});
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  /// The next frame, or nullopt after the last one. Rethrows a decoding error (InputError) at
  /// the frame that caused it.
  std::optional<RgbdFrame> next();

 private:
  void run();

  const Sequence& sequence_;
  const std::size_t capacity_;
  const Prepare prepare_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<RgbdFrame> ready_;
  std::exception_ptr error_;
  bool done_ = false;
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace vdmap
