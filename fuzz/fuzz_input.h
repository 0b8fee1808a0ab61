#pragma once
// Shared by the fuzz targets: the readers under test take a path, so each input is written to a
// file in a per-process scratch folder first.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace vdmap::fuzz {

/// Writes the input to `name` in this process's scratch folder and returns its path.
inline std::filesystem::path writeInput(const std::uint8_t* data, std::size_t size, const std::string& name) {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("vdmap-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::filesystem::path file = dir / name;
  std::filesystem::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return file;
}

}  // namespace vdmap::fuzz

/// Runs `call`; the readers' documented error for a bad file (InputError) is an expected outcome,
/// anything else escapes and libFuzzer reports it as a crash.
#define VDMAP_FUZZ_EXPECTED_ERRORS(call) \
  try {                                  \
    call;                                \
  } catch (const ::vdmap::InputError&) { \
  }
