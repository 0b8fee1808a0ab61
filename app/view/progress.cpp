#include "app/view/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <exception>

namespace vdmap::app {

ProgressBar::ProgressBar(std::string label, std::size_t total)
    : label_(std::move(label)), total_(total), enabled_(isatty(STDERR_FILENO) != 0),
      exceptions_(std::uncaught_exceptions()) {}

ProgressBar::~ProgressBar() {
  if (!enabled_) return;
  if (std::uncaught_exceptions() == exceptions_) draw(total_);
  std::fputc('\n', stderr);
}

void ProgressBar::update(std::size_t done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100) && done < total_) return;
  last_draw_ = now;
  draw(done);
}

void ProgressBar::draw(std::size_t done) {
  constexpr int kWidth = 40;
  const double fraction = total_ == 0 ? 1.0 : std::min(1.0, static_cast<double>(done) / static_cast<double>(total_));
  const int filled = static_cast<int>(fraction * kWidth);
  std::fprintf(stderr, "\r%s [%.*s%*s] %zu/%zu", label_.c_str(), filled, "########################################",
               kWidth - filled, "", done, total_);
  std::fflush(stderr);
}

}  // namespace vdmap::app
