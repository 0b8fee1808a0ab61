#pragma once
// Per-frame records (stage times, the trajectory) that the mapping worker appends to and the UI
// reads through snapshots: a snapshot shares the records instead of copying them, so publishing
// one per frame stays O(1) and not O(frames mapped).
#include <algorithm>
#include <cstddef>
#include <memory>
#include <span>

namespace vdmap::app::gui {

/// The first items of an AppendLog as they were when taken; holds their storage, so it stays
/// valid and unchanged whatever is appended later. Read it like a std::span.
template <typename T>
struct SharedSpan : std::span<const T> {
  std::shared_ptr<const T[]> storage;
};

/// An append-only array for one writer thread. Items are never moved or overwritten once
/// appended: a full buffer is copied into a twice larger one, and views keep the old one. So a
/// view handed to another thread under a lock (which orders the writes before it) may be read
/// there without further locking while the writer goes on appending.
template <typename T>
class AppendLog {
 public:
  void push_back(const T& item) {
    if (size_ == capacity_) {
      capacity_ = std::max<std::size_t>(256, 2 * capacity_);
      std::shared_ptr<T[]> bigger = std::make_shared<T[]>(capacity_);
      std::copy_n(buffer_.get(), size_, bigger.get());
      buffer_ = std::move(bigger);
    }
    buffer_[size_++] = item;  // past every view taken so far
  }
  /// Empties the log; views taken before keep their items.
  void clear() { *this = AppendLog(); }
  std::size_t size() const { return size_; }
  SharedSpan<T> view() const { return {{buffer_.get(), size_}, buffer_}; }

 private:
  std::shared_ptr<T[]> buffer_;
  std::size_t size_ = 0, capacity_ = 0;
};

}  // namespace vdmap::app::gui
