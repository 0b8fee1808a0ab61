#pragma once
// The options every verb that reads a sequence shares, and opening the sequence they name.
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "mapping/pipeline/mapper.h"
#include "mapping/sequence/sequence.h"

namespace vdmap::app {

/// The options every verb that reads a sequence shares: SEQ, --camera, --frames, and for the
/// verbs that map it --poses.
struct SequenceArgs {
  std::string folder;
  std::string camera{};
  std::string frames{};
  std::string poses{};  ///< "gt", "track" or empty: gt when the folder has groundtruth.txt, else track
  std::string refine =
      "joint";  ///< tracked poses: "joint", "pairwise" or "none" (MapRefinementMethod; none: keep them as tracked)
  bool refine_given = false;  ///< --refine was on the command line
  SequenceOptions::Topics
      topics{};  ///< a recording's --depth-topic, --rgb-topic, --info-topic, --pose-topic, --pose-frames
  double rgb_window_s = SequenceOptions{}.max_rgb_dt_s;  ///< --rgb-window
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
PoseSource poseSource(const SequenceArgs& args, const Sequence& sequence);
/// The flags that open the frames `args` names as given (" --camera kinect --frames 0:150", ""
/// when none): for the commands the workbench prints. --refine only when refine_given.
std::string sequenceFlags(const SequenceArgs& args);
/// The camera preset names, comma-separated, for --camera help texts.
std::string cameraPresetList();

/// Opens the sequence the arguments name (throws InputError / std::invalid_argument). With
/// --poses track (or no --poses and no groundtruth.txt) frames without ground truth are kept.
/// `cut_range_at_end`: a --frames range past the end is cut there (a verb's default range)
/// instead of refused. `continues`: the session the sequence continues (SequenceOptions::continues).
Sequence openSequence(const SequenceArgs& args, bool cut_range_at_end = false,
                      std::optional<SequenceContinuation> continues = std::nullopt);
/// When no --camera or camera file chose the sequence's camera, says on stderr, in one line,
/// which preset was guessed and why ("vdmap VERB: note: ..."): a wrong guess maps without error.
void noteCameraGuess(const Sequence& sequence, const std::string& verb);

}  // namespace vdmap::app
