#pragma once
#include <filesystem>
#include <functional>
#include <string_view>

namespace vdmap {

/// Writes `bytes` to a temporary file beside `file`, fsyncs it and renames it into place (atomic
/// on POSIX within a folder; the folder is fsynced after), so a reader, an interrupted run or a
/// power cut never sees a half-written file. Throws std::runtime_error naming `file` and the
/// reason when it cannot be written; no temporary is left behind (an interrupt removes it too when
/// installTemporaryPathCleanup() is in place; a SIGKILL leaves it, and the next write of `file`
/// removes it once its process is gone).
void writeFileAtomically(const std::filesystem::path& file, std::string_view bytes);

/// Receives a file's bytes piece by piece, in order.
using ByteSink = std::function<void(std::string_view)>;

/// writeFileAtomically of the bytes `produce` hands to its sink, written as they come, so a large
/// file (a session) is never held whole in memory. An exception from `produce` removes the
/// temporary file and propagates; the old file stays.
void writeFileAtomically(const std::filesystem::path& file, const std::function<void(const ByteSink&)>& produce);

}  // namespace vdmap
