#include "mapping/core/atomic_file.h"

#include <unistd.h>

#include <fstream>
#include <stdexcept>
#include <string>

namespace vdmap {

void writeFileAtomically(const std::filesystem::path& file, std::string_view bytes) {
  const std::filesystem::path tmp = file.string() + ".tmp-" + std::to_string(::getpid());
  bool written = false;
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (out) {
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      out.flush();
      written = static_cast<bool>(out);
    }
  }
  std::error_code ec;
  if (written) std::filesystem::rename(tmp, file, ec);
  if (!written || ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(file.string() + ": cannot write (is the folder there, writable, not full?)");
  }
}

}  // namespace vdmap
