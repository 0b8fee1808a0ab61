#pragma once
// Loops on a given number of TBB threads whose result does not depend on that number.
#include <cstddef>

#include <algorithm>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

namespace vdmap {

/// The most threads a loop may be asked for (GlobalMapParams::threads, `--threads`): far more than
/// any machine vdmap runs on has cores, far fewer than the thousands at which TBB's allocator fails.
inline constexpr int kMaxThreads = 256;

/// The threads a loop asked for `threads` (0: all) runs on: at most as many as TBB allows the
/// process (its cores, or a tbb::global_control limit). TBB would ignore the extra ones anyway, but
/// an arena asking for more prints a warning on stderr.
inline int arenaThreads(int threads) {
  const int allowed = static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  return threads > 0 ? std::min(threads, std::max(allowed, 1)) : tbb::task_arena::automatic;
}

/// Runs body(i) for i in [0, n) on `threads` threads (0: all). Each i must write only its own
/// slot, so the result is the same for any thread count.
template <typename Body>
void parallelFor(int threads, std::size_t n, const Body& body) {
  tbb::task_arena arena(arenaThreads(threads));
  arena.execute([&] { tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) { body(i); }); });
}

/// Sorts [begin, end) on `threads` threads (0: all). Only for elements without ties (an index in
/// each), so the unstable parallel sort still gives the one sorted order whatever the thread count.
template <typename Iterator>
void parallelSort(int threads, Iterator begin, Iterator end) {
  tbb::task_arena arena(arenaThreads(threads));
  arena.execute([&] { tbb::parallel_sort(begin, end); });
}

}  // namespace vdmap
