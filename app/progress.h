#pragma once
#include <chrono>
#include <cstddef>
#include <string>

namespace vdmap::app {

/// A one-line progress bar on stderr for long work; silent when stderr is not a terminal so
/// that logs and --json output stay clean. Not thread-safe: update from one thread.
class ProgressBar {
 public:
  ProgressBar(std::string label, std::size_t total);
  ~ProgressBar();
  void update(std::size_t done);

 private:
  void draw(std::size_t done);

  std::string label_;
  std::size_t total_;
  bool enabled_;
  std::chrono::steady_clock::time_point last_draw_{};
};

}  // namespace vdmap::app
