#pragma once
#include <chrono>
#include <cstddef>
#include <new>
#include <stdexcept>
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
/// save). Returns what `work` returns; memory running out in it is the error "out of memory
/// building the LABEL: ..." (std::bad_alloc says nothing of what was being built).
template <typename Work>
auto withStageBar(const std::string& label, Work&& work) {
  ProgressBar bar(label, 1);
  bar.update(0);
  try {
    return work();
  } catch (const std::bad_alloc&) {
    throw std::runtime_error("out of memory building the " + label +
                             ": give fewer frames or coarser settings, or run where more memory is free");
  }
}

}  // namespace vdmap::app
