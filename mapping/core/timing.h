#pragma once
// Wall-clock stopwatch helpers for the timings reported with maps and frames.
#include <chrono>

namespace vdmap {

inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

inline double msSince(std::chrono::steady_clock::time_point start) { return 1e3 * secondsSince(start); }

}  // namespace vdmap
