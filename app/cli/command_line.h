#pragma once
// What the verbs share on the command line: the exit code of a verb that did its work but
// found a difference, option checks run while the command line is parsed, output-file checks.

#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

#include "mapping/core/message_text.h"

namespace vdmap::app {

/// Ends a verb with an exit code other than 0 and 1 after it did its work: `vdmap render
/// --expect/--suite` rendered, but an image differs from its golden (code 2, docs/cli.md "Exit
/// codes and errors"). main() prints "vdmap VERB: differs: WHAT" (one line) and returns `code`.
struct ExitWith : std::runtime_error {
  ExitWith(int exit_code, const std::string& what) : std::runtime_error(what), code(exit_code) {}
  int code;
};

/// `text` as one shell word: as it is when it needs no quoting, else in single quotes.
std::string shellQuoted(const std::string& text);

/// CLI11's help with every line wrapped at `width` columns: long descriptions go on under their
/// own column, as a terminal shows them best (CLI11 prints each on one line).
class WrappingFormatter : public CLI::Formatter {
 public:
  explicit WrappingFormatter(std::size_t width) : width_(width) {}
  std::string make_help(const CLI::App* app, std::string name, CLI::AppFormatMode mode) const override;

 private:
  std::size_t width_;
};

// CLI11 checks of an option's value by itself, while the command line is parsed: a value that is
// wrong whatever the files hold gets CLI11's error and code (docs/cli.md "Exit codes and
// errors"); what needs a file or the data is checked by the verb (exit 1).

/// A camera preset name (cameraPresetNames).
CLI::Validator cameraPresetCheck();
/// A --frames range's syntax (A:B, A:, :B or N; numbers within an int; B after A).
CLI::Validator frameRangeCheck();
/// A finite number > 0 (and at most `most`).
CLI::Validator positiveFiniteCheck(std::optional<double> most = std::nullopt);
/// A finite number.
CLI::Validator finiteCheck();
/// Accepts a value when `parse(value)` does not throw std::invalid_argument, whose message is
/// then the error (CLI11 puts the option's name before it).
template <typename Parse>
CLI::Validator parsedBy(Parse parse, const std::string& description) {
  return CLI::Validator(
      [parse](std::string& text) -> std::string {
        try {
          parse(text);
          return "";
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      },
      description);
}

/// Fails before any work when `file`, given as `option`, cannot become an output file: it is a
/// folder, its folder does not exist or cannot be written (permissions, a read-only file
/// system), or a file stands where a folder of its path should be (throws std::invalid_argument).
inline void checkOutputFile(const std::string& file, const std::string& option) {
  namespace fs = std::filesystem;
  if (fs::is_directory(file)) throw std::invalid_argument(file + ": is a folder (" + option + " wants a file)");
  const fs::path folder = fs::absolute(file).parent_path();
  if (fs::is_directory(folder)) {
    // The file is written beside itself and renamed into place: the folder must take new files.
    if (::access(folder.c_str(), W_OK | X_OK) != 0)
      throw std::invalid_argument(file + ": cannot write into " + folder.string() + " (" + std::strerror(errno) + ", " +
                                  option + ")");
    return;
  }
  fs::path existing = folder;  // the nearest part of the path that exists
  while (!fs::exists(existing) && existing.has_parent_path() && existing.parent_path() != existing)
    existing = existing.parent_path();
  if (fs::exists(existing) && !fs::is_directory(existing))
    throw std::invalid_argument(file + ": " + existing.string() + " is a file, not a folder (" + option + ")");
  throw std::invalid_argument(file + ": its folder does not exist (" + option + ")");
}

/// Fails before any work when `file` does not name a mesh file vdmap writes (.ply or .obj, any case).
inline void checkMeshFileName(const std::string& file) {
  std::string ext = std::filesystem::path(file).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".ply" && ext != ".obj") throw std::invalid_argument(file + ": a mesh is written as .ply or .obj");
}

/// Fails before any work when the output `file` (given as `option`) is one of `inputs` ({option,
/// path} pairs; empty paths skipped) by any path to it: writing it would destroy what is read.
inline void checkNotAnInput(const std::string& file, const std::string& option,
                            std::initializer_list<std::pair<const char*, std::string>> inputs) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const auto& [input_option, input] : inputs) {
    if (input.empty() || file.empty()) continue;
    const bool same = fs::exists(file, ec) && fs::exists(input, ec)
                          ? fs::equivalent(file, input, ec)
                          : fs::weakly_canonical(file, ec) == fs::weakly_canonical(input, ec);
    if (same)
      throw std::invalid_argument(file + ": " + option + " is the file " + input_option +
                                  " reads; write the output elsewhere");
  }
}

}  // namespace vdmap::app
