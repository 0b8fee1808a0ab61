#pragma once
// Returning freed heap memory to the system after a large transient allocation.
#include <malloc.h>

namespace vdmap::app {

/// A global-map build allocates and frees hundreds of MB of temporaries (sorted buckets, merge
/// and fusion candidates) on several threads; glibc keeps what was freed in its per-thread
/// arenas, so a long-running process's resident size drifts with whichever build peaked last,
/// well above its live heap (docs/notes/performance.md, "Long runs"). Called
/// after each build by the processes that build repeatedly (the workbench, bench --long), and by
/// vdmap map once before its build, so the frames' freed buffers do not add to the build's peak.
inline void releaseFreedMemory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

}  // namespace vdmap::app
