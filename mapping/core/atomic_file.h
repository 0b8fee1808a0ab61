#pragma once
#include <filesystem>
#include <string_view>

namespace vdmap {

/// Writes `bytes` to a temporary file beside `file` and renames it into place (atomic on POSIX
/// within a folder), so a reader, or an interrupted run, never sees a half-written file. Throws
/// std::runtime_error naming `file` when it cannot be written; no temporary is left behind.
void writeFileAtomically(const std::filesystem::path& file, std::string_view bytes);

}  // namespace vdmap
