#pragma once
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "mapping/io/tum_sequence.h"

namespace vdmap {

/// Decodes the frames of a sequence in order on a background thread, at most `capacity` ahead
/// of the consumer, so decoding overlaps mapping and memory stays bounded. One consumer thread.
class FramePrefetcher {
 public:
  /// `sequence` must outlive the prefetcher.
  explicit FramePrefetcher(const TumSequence& sequence, std::size_t capacity = 4);
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  /// The next frame, or nullopt after the last one. Rethrows a decoding error (InputError) at
  /// the frame that caused it.
  std::optional<RgbdFrame> next();

 private:
  void run();

  const TumSequence& sequence_;
  const std::size_t capacity_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<RgbdFrame> ready_;
  std::exception_ptr error_;
  bool done_ = false;
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace vdmap
