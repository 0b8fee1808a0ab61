#pragma once
// Timing helpers shared by the verbs that report speed.
#include <algorithm>
#include <chrono>
#include <vector>

namespace vdmap::app {

/// Median of the values (0 for none); figures are quoted as medians, never single runs.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Wall time of f(), milliseconds.
template <typename F>
double timeMs(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace vdmap::app
