#pragma once
// Timing helpers shared by the verbs that report speed.
#include <algorithm>
#include <ctime>
#include <vector>

namespace vdmap::app {

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

}  // namespace vdmap::app
