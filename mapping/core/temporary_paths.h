#pragma once
// Temporary files and folders that an interrupted run must not leave behind: a process-wide
// registry that a SIGINT/SIGTERM handler empties. Writers register what they create for as long
// as it is temporary (writeFileAtomically's FILE.tmp-PID, the export's staging folder); the
// handler unlinks the files, removes the folders (which hold only registered files) and lets the
// signal end the process as it would have. A SIGKILL or a power cut still leaves them: those are
// found by name on the next run (map_export.cpp's stale staging folders).
#include <filesystem>
#include <string>

namespace vdmap {

/// Registers `path` for removal on an interrupt while the object lives; destruction only
/// unregisters (the owner removes or renames the path itself). Best effort: a path longer than
/// PATH_MAX or beyond the registry's 256 slots is not registered. Thread-safe.
class TemporaryPath {
 public:
  /// `folder`: removed with rmdir after every registered file is unlinked (only when empty by then).
  explicit TemporaryPath(const std::filesystem::path& path, bool folder = false);
  ~TemporaryPath();
  TemporaryPath(const TemporaryPath&) = delete;
  TemporaryPath& operator=(const TemporaryPath&) = delete;

 private:
  int slot_ = -1;
};

/// True when `name` is `prefix` followed by the id of a process that no longer exists (not this
/// one): a temporary that a killed run (SIGKILL, a power cut) left, which a later run may remove.
bool isStaleTemporaryName(const std::string& name, const std::string& prefix);

/// Unlinks every registered file, then removes every registered folder. Async-signal-safe.
void removeTemporaryPaths();

/// Installs SIGINT, SIGTERM and SIGHUP handlers that call removeTemporaryPaths() and then end the
/// process with the same signal (default action), so the exit status still says "interrupted".
/// Also ignores SIGXFSZ, so a write past `ulimit -f` fails with EFBIG like any write error.
/// For executables (vdmap's main); a library never installs it on its own.
void installTemporaryPathCleanup();

}  // namespace vdmap
