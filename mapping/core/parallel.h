#pragma once
// Loops on a given number of TBB threads whose result does not depend on that number.
#include <cstddef>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

namespace vdmap {

/// Runs body(i) for i in [0, n) on `threads` threads (0: all). Each i must write only its own
/// slot, so the result is the same for any thread count.
template <typename Body>
void parallelFor(int threads, std::size_t n, const Body& body) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] { tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) { body(i); }); });
}

/// Sorts [begin, end) on `threads` threads (0: all). Only for elements without ties (an index in
/// each), so the unstable parallel sort still gives the one sorted order whatever the thread count.
template <typename Iterator>
void parallelSort(int threads, Iterator begin, Iterator end) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] { tbb::parallel_sort(begin, end); });
}

}  // namespace vdmap
