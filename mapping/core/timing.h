#pragma once
// Timing helpers: wall-clock stopwatches for the timings reported with maps and frames, the
// process's CPU time and the median that every speed figure is quoted as.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <vector>

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

/// Median of the values (0 for none); figures are quoted as medians, never single runs.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// CPU time of the whole process spent in f(), milliseconds. For single-threaded work on a
/// shared machine: unlike wall time it does not count the time other processes held the core,
/// which inflates short tasks (a 3 ms update preempted once waits a whole time slice) far more
/// than long ones and so skews ratios. Run nothing else in the process meanwhile.
template <typename F>
double cpuTimeMs(F&& f) {
  timespec a{}, b{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  f();
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  return 1e3 * static_cast<double>(b.tv_sec - a.tv_sec) + 1e-6 * static_cast<double>(b.tv_nsec - a.tv_nsec);
}

/// The median of `passes` runs of cpuTimeMs(f), milliseconds.
template <typename F>
double medianCpuTimeMs(int passes, F&& f) {
  std::vector<double> ms;
  for (int pass = 0; pass < passes; ++pass) ms.push_back(cpuTimeMs(f));
  return median(ms);
}

}  // namespace vdmap
