#include "mapping/core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "mapping/core/temporary_paths.h"

namespace vdmap {
namespace {

bool writeAll(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

// Makes the rename itself durable; failure here does not undo a completed write.
void syncFolder(const std::filesystem::path& folder) {
  const int fd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// Removes FILE.tmp-PID files that runs killed while writing `file` left (a session can be tens of
// MB); those of live processes are theirs.
void removeStaleTemporaries(const std::filesystem::path& file) {
  const std::string prefix = file.filename().string() + ".tmp-";
  const std::filesystem::path folder = file.has_parent_path() ? file.parent_path() : ".";
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code ignored;
    if (isStaleTemporaryName(it->path().filename().string(), prefix)) std::filesystem::remove(it->path(), ignored);
  }
}

}  // namespace

void writeFileAtomically(const std::filesystem::path& file, std::string_view bytes) {
  writeFileAtomically(file, [bytes](const ByteSink& sink) { sink(bytes); });
}

void writeFileAtomically(const std::filesystem::path& file, const std::function<void(const ByteSink&)>& produce) {
  removeStaleTemporaries(file);
  const std::filesystem::path tmp = file.string() + ".tmp-" + std::to_string(::getpid());
  const TemporaryPath interrupt_cleanup(tmp);
  // The data reaches the disk before the rename publishes it, so a crash or power loss at any
  // moment leaves the old file or the complete new one.
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool written = fd >= 0;
  int error = errno;
  struct WriteFailed {};  // stops `produce` at the first piece that cannot be written
  try {
    if (written)
      produce([&](std::string_view piece) {
        if (!writeAll(fd, piece)) {
          error = errno;
          throw WriteFailed{};
        }
      });
  } catch (const WriteFailed&) {
    written = false;
  } catch (...) {
    ::close(fd);
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
  if (written && ::fsync(fd) != 0) written = false, error = errno;
  if (fd >= 0 && ::close(fd) != 0 && written) written = false, error = errno;
  std::error_code ec;
  if (written) std::filesystem::rename(tmp, file, ec);
  if (!written || ec) {
    const std::string reason = written ? ec.message() : std::strerror(error);
    std::filesystem::remove(tmp, ec);  // overwrites ec, hence the reason first
    throw std::runtime_error(file.string() + ": cannot write (" + reason + ")");
  }
  syncFolder(file.parent_path());
}

}  // namespace vdmap
