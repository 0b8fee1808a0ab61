#pragma once
// What an exception says to the user: one line naming the path and what is wrong, never a
// library's own text ("filesystem error: status: ...", "std::bad_alloc").

#include <cctype>
#include <exception>
#include <filesystem>
#include <new>
#include <string>

namespace vdmap::app {

/// `path` cut to its first and last characters when long, for a one-line message.
inline std::string shortPath(const std::string& path) {
  return path.size() <= 80 ? path : path.substr(0, 50) + "..." + path.substr(path.size() - 27);
}

/// The message of `e`: a path the system cannot look up (a symbolic-link loop, a name too long)
/// is the path and why; memory running out says so and what to do; anything else its what().
inline std::string errorMessage(const std::exception& e) {
  if (const auto* fs_error = dynamic_cast<const std::filesystem::filesystem_error*>(&e)) {
    std::string why = fs_error->code().message();
    if (!why.empty()) why[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(why[0])));
    return fs_error->path1().empty() ? why : shortPath(fs_error->path1().string()) + ": " + why;
  }
  if (dynamic_cast<const std::bad_alloc*>(&e))
    return "out of memory: give fewer frames or coarser settings, or run where more memory is free";
  return e.what();
}

}  // namespace vdmap::app
