#pragma once
// Wall-clock stopwatch helpers for the timings reported with maps and frames.
#include <chrono>
#include <cstdio>
#include <cstdlib>

namespace vdmap {

inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

inline double msSince(std::chrono::steady_clock::time_point start) { return 1e3 * secondsSince(start); }

/// `v` rounded to `digits` significant digits, for figures written to JSON or markdown: a
/// timing or a share is not known to 17 digits, and 0.37012345678901 only hides the number.
inline double rounded(double v, int digits = 5) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return std::strtod(text, nullptr);
}

}  // namespace vdmap
