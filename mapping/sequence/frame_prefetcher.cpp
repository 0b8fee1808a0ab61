#include "mapping/sequence/frame_prefetcher.h"

namespace vdmap {

FramePrefetcher::FramePrefetcher(const Sequence& sequence, std::size_t capacity, Prepare prepare)
    : sequence_(sequence), capacity_(capacity < 1 ? 1 : capacity), prepare_(std::move(prepare)),
      worker_([this] { run(); }) {}

FramePrefetcher::~FramePrefetcher() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void FramePrefetcher::run() {
  for (std::size_t i = 0; i < sequence_.size(); ++i) {
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return stop_ || ready_.size() < capacity_; });
      if (stop_) return;
    }
    try {
      RgbdFrame frame = sequence_.load(i);
      if (prepare_) prepare_(frame);
      std::lock_guard lock(mutex_);
      ready_.push_back(std::move(frame));
    } catch (...) {
      std::lock_guard lock(mutex_);
      error_ = std::current_exception();
      break;
    }
    changed_.notify_all();
  }
  {
    std::lock_guard lock(mutex_);
    done_ = true;
  }
  changed_.notify_all();
}

std::optional<RgbdFrame> FramePrefetcher::next() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return !ready_.empty() || done_; });
  if (!ready_.empty()) {
    RgbdFrame frame = std::move(ready_.front());
    ready_.pop_front();
    lock.unlock();
    changed_.notify_all();
    return frame;
  }
  if (error_) std::rethrow_exception(error_);
  return std::nullopt;
}

}  // namespace vdmap
