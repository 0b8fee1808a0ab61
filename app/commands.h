#pragma once
// Each verb of the vdmap command registers itself on the top-level CLI11 app. A verb's callback
// throws std::exception on failure; main() turns that into a one-line error and exit code 1.

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

namespace vdmap::app {

void addInfoCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addSynthCommand(CLI::App& app);
void addMapCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addEvalCommand(CLI::App& app);
void addGuiCommand(CLI::App& app);
/// `vdmap query MAP --op ...`: point queries and the planners' exports (docs/method.md 13).
void addQueryCommand(CLI::App& app);
/// `vdmap params [--markdown]`: the parameter table for users, or docs/parameters.md.
void addParamsCommand(CLI::App& app);
/// The workbench options of `vdmap` without a verb; the returned function opens the workbench
/// on the built-in scene (throws std::runtime_error when it ends on an error).
std::function<void()> addBuiltinWorkbenchOptions(CLI::App& app);

/// Ends a verb with an exit code other than 0 and 1 after it did its work: `vdmap render
/// --expect/--suite` rendered, but an image differs from its golden (code 2, docs/cli.md "Exit
/// codes and errors"). main() prints "vdmap VERB: differs: WHAT" (one line) and returns `code`.
struct ExitWith : std::runtime_error {
  ExitWith(int exit_code, const std::string& what) : std::runtime_error(what), code(exit_code) {}
  int code;
};

/// "1 keyframe", "2 keyframes": a count with its noun (regular plurals only).
inline std::string counted(long long n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

// CLI11 checks of an option's value by itself, while the command line is parsed: a value that is
// wrong whatever the files hold gets CLI11's error and code (docs/cli.md "Exit codes and
// errors"); what needs a file or the data is checked by the verb (exit 1).

/// A camera preset name (cameraPresetNames).
CLI::Validator cameraPresetCheck();
/// A --frames range's syntax (A:B, A:, :B or N; numbers within an int; B after A).
CLI::Validator frameRangeCheck();
/// A finite number > 0.
CLI::Validator positiveFiniteCheck();
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

}  // namespace vdmap::app

#include "mapping/io/tum_sequence.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap::app {

/// The options every verb that reads a sequence shares: SEQ, --camera, --frames, and for the
/// verbs that map it --poses.
struct SequenceArgs {
  std::string folder;
  std::string camera;
  std::string frames;
  std::string poses;  ///< "gt", "track" or empty: gt when the folder has groundtruth.txt, else track
  std::string refine = "joint";  ///< tracked poses: "joint", "pairwise" or "none" (MapRefinementMethod; none: keep them as tracked)
  bool refine_given = false;     ///< --refine was on the command line
};
/// SEQ, --camera (a preset name, checked while parsing) and --frames (its syntax checked while
/// parsing; whether the sequence has those frames when it is opened).
void addSequenceArgs(CLI::App& verb, SequenceArgs& args);
/// --poses gt|track, for the verbs that map a sequence.
void addPoseSourceArg(CLI::App& verb, SequenceArgs& args);
/// --refine METHOD and --no-refine, for the verbs that map a whole sequence (map, render SEQ).
void addRefineArg(CLI::App& verb, SequenceArgs& args);
/// The refinement --refine names (nullopt: none).
std::optional<MapRefinementParams> refinement(const SequenceArgs& args);
/// Refuses a --refine joint|pairwise given for a run of ground-truth poses, which it would not
/// change (refinement corrects tracked poses, docs/method.md 10): throws std::invalid_argument.
void checkRefinementApplies(const SequenceArgs& args, PoseSource poses);
/// The pose source --poses names for an opened sequence (the default: gt when it has ground truth).
PoseSource poseSource(const SequenceArgs& args, const TumSequence& sequence);
/// The camera preset names, comma-separated, for --camera help texts.
std::string cameraPresetList();

/// Opens the sequence the arguments name (throws InputError / std::invalid_argument). With
/// --poses track (or no --poses and no groundtruth.txt) frames without ground truth are kept.
/// `cut_range_at_end`: a --frames range past the end is cut there (a verb's default range)
/// instead of refused. `continues`: the session the sequence continues (SequenceOptions::continues).
TumSequence openSequence(const SequenceArgs& args, bool cut_range_at_end = false,
                         std::optional<SequenceContinuation> continues = std::nullopt);
/// When no --camera or camera file chose the sequence's camera, says on stderr, in one line,
/// which preset was guessed and why ("vdmap VERB: note: ..."): a wrong guess maps without error.
void noteCameraGuess(const TumSequence& sequence, const std::string& verb);

}  // namespace vdmap::app
