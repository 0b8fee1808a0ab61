#pragma once
#include <chrono>
#include <cstddef>
#include <string>
#include <utility>

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
  int exceptions_ = 0;  // std::uncaught_exceptions() when made: a bar unwound by an error is not completed
};

/// Runs `work` under a one-step bar named `label`, drawn when it starts and completed when it
/// ends: for a long stage that does not report its own progress (the global-map build, a session
/// save). Returns what `work` returns.
template <typename Work>
auto withStageBar(std::string label, Work&& work) {
  ProgressBar bar(std::move(label), 1);
  bar.update(0);
  return work();
}

}  // namespace vdmap::app
