#include "mapping/core/temporary_paths.h"

#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <signal.h>
#include <unistd.h>

#include <atomic>

namespace vdmap {
namespace {

// Fixed storage, no allocation: the signal handler reads it. A slot is published (kReady) only
// once its path is complete.
constexpr int kSlots = 256;
enum SlotState : int { kFree = 0, kWriting = 1, kReady = 2 };
struct PathSlot {
  std::atomic<int> state{kFree};
  bool folder = false;
  char path[PATH_MAX] = {};
};
PathSlot g_slots[kSlots];
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler reads the slots' state");

void onInterrupt(int signal) {
  removeTemporaryPaths();
  // SA_RESETHAND restored the default action; the signal is blocked in here, so it ends the
  // process once the handler returns.
  ::raise(signal);
}

}  // namespace

TemporaryPath::TemporaryPath(const std::filesystem::path& path, bool folder) {
  const std::string& text = path.native();
  if (text.empty() || text.size() >= PATH_MAX) return;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kWriting)) continue;
    std::memcpy(g_slots[i].path, text.c_str(), text.size() + 1);
    g_slots[i].folder = folder;
    g_slots[i].state.store(kReady, std::memory_order_release);
    slot_ = i;
    return;
  }
}

TemporaryPath::~TemporaryPath() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
}

bool isStaleTemporaryName(const std::string& name, const std::string& prefix) {
  if (name.rfind(prefix, 0) != 0) return false;
  const std::string digits = name.substr(prefix.size());
  if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return false;
  const pid_t pid = static_cast<pid_t>(std::stol(digits));
  return pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH;
}

void removeTemporaryPaths() {
  // Files first; then folders, a few passes, so a folder holding another registered folder goes
  // whatever their slot order (rmdir removes only empty ones).
  for (const int pass : {0, 1, 2, 3})
    for (PathSlot& slot : g_slots)
      if (slot.state.load(std::memory_order_acquire) == kReady && slot.folder == (pass > 0))
        pass > 0 ? ::rmdir(slot.path) : ::unlink(slot.path);
}

void installTemporaryPathCleanup() {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    ::sigaction(signal, nullptr, &old);
    if (old.sa_handler == SIG_IGN) continue;  // e.g. SIGHUP under nohup: stay immune
    struct sigaction action {};
    action.sa_handler = onInterrupt;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal, &action, nullptr);
  }
  // A file grown past `ulimit -f` would end the process by SIGXFSZ, with no message and its
  // temporary files left; ignored, the write fails with EFBIG ("File too large") and is reported
  // and cleaned up as a full disk is.
  ::signal(SIGXFSZ, SIG_IGN);
}

}  // namespace vdmap
