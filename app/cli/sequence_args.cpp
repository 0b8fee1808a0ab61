#include <cstdio>

#include "app/cli/command_line.h"
#include "app/cli/sequence_args.h"
#include "mapping/io/camera_config.h"

namespace vdmap::app {

std::string cameraPresetList() {
  std::string presets;
  for (const std::string& n : cameraPresetNames()) presets += (presets.empty() ? "" : ", ") + n;
  return presets;
}

void addSequenceArgs(CLI::App& verb, SequenceArgs& args) {
  verb.add_option(
          "SEQ", args.folder,
          "the sequence: a TUM RGB-D, 7-Scenes, Replica (NICE-SLAM) or ScanNet folder, a ROS 1 bag or an MCAP file (docs/cli.md, Sequences)")
      ->required();
  verb.add_option("--camera", args.camera, "camera preset overriding the folder's: " + cameraPresetList())
      ->check(cameraPresetCheck());
  verb.add_option("--frames", args.frames,
                  "frames A:B of the depth list (B exclusive; A: or :B; a plain N means 0:N, the first N frames); "
                  "a range past the end is an error")
      ->check(frameRangeCheck());
  verb.add_option("--rgb-window", args.rgb_window_s,
                  "seconds: a depth frame takes the colour image nearest in time within this (sensors that do not "
                  "trigger colour and depth together need more)")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  verb.add_option("--depth-topic", args.topics.depth, "a recording's depth topic (default: found by type and name)");
  verb.add_option("--rgb-topic", args.topics.rgb, "a recording's colour topic (default: found by type and name)");
  verb.add_option("--info-topic", args.topics.info,
                  "a recording's depth camera_info topic (default: the one nearest the depth topic)");
  verb.add_option("--pose-topic", args.topics.pose,
                  "a recording's poses from a geometry_msgs/PoseStamped or nav_msgs/Odometry topic instead of tf");
  verb.add_option_function<std::string>(
      "--pose-frames",
      [&args](const std::string& text) {
        const auto colon = text.find(':');
        if (colon == std::string::npos || colon == 0 || colon + 1 == text.size())
          throw CLI::ValidationError("--pose-frames", "expected WORLD:CAMERA, two tf frame names");
        args.topics.world_frame = text.substr(0, colon);
        args.topics.camera_frame = text.substr(colon + 1);
      },
      "a recording's tf frames the poses are taken between (default: the tree's root and the depth image's "
      "frame_id)");
}

void addPoseSourceArg(CLI::App& verb, SequenceArgs& args) {
  verb.add_option("--poses", args.poses,
                  "gt: the sequence's groundtruth.txt; track: estimate every pose (tracking, loop closure, "
                  "pose graph). Default: gt when the sequence has groundtruth.txt, else track")
      ->check(CLI::IsMember({"gt", "track"}));
}

void addRefineArg(CLI::App& verb, SequenceArgs& args) {
  verb.add_option("--refine", args.refine,
                  "with tracked poses, how the keyframe poses are refined from the settled local maps after the "
                  "last frame: joint (all keyframe poses at once on every covisible pair's cost), pairwise (each "
                  "covisible pair registered, then the pose graph) or none (as tracked and loop-closed); see "
                  "docs/method.md 10")
      ->check(CLI::IsMember({"joint", "pairwise", "none"}))
      ->each([&args](const std::string&) { args.refine_given = true; })
      ->capture_default_str();
  verb.add_flag_callback(
      "--no-refine", [&args] { args.refine = "none"; }, "same as --refine none");
}

std::string sequenceFlags(const SequenceArgs& args) {
  std::string flags;
  const auto add = [&flags](const char* flag, const std::string& value) {
    if (!value.empty()) flags += std::string(" ") + flag + " " + shellQuoted(value);
  };
  add("--camera", args.camera);
  add("--frames", args.frames);
  if (args.rgb_window_s != SequenceArgs{}.rgb_window_s) {
    char window[32];
    std::snprintf(window, sizeof window, "%g", args.rgb_window_s);
    add("--rgb-window", window);
  }
  add("--depth-topic", args.topics.depth);
  add("--rgb-topic", args.topics.rgb);
  add("--info-topic", args.topics.info);
  add("--pose-topic", args.topics.pose);
  if (!args.topics.world_frame.empty()) add("--pose-frames", args.topics.world_frame + ":" + args.topics.camera_frame);
  add("--poses", args.poses);
  if (args.refine_given) add("--refine", args.refine);
  return flags;
}

std::optional<MapRefinementParams> refinement(const SequenceArgs& args) {
  if (args.refine == "none") return std::nullopt;
  MapRefinementParams params;
  params.method = args.refine == "pairwise" ? MapRefinementMethod::kPairwise : MapRefinementMethod::kJoint;
  return params;
}

void checkRefinementApplies(const SequenceArgs& args, PoseSource poses) {
  if (poses == PoseSource::kTrack || !args.refine_given || args.refine == "none") return;
  throw std::invalid_argument("--refine " + args.refine +
                              " refines tracked poses (--poses track); this run maps the ground-truth poses of "
                              "groundtruth.txt, which it would leave as they are");
}

PoseSource poseSource(const SequenceArgs& args, const Sequence& sequence) {
  if (args.poses.empty()) return sequence.hasGroundTruth() ? PoseSource::kGroundTruth : PoseSource::kTrack;
  return args.poses == "track" ? PoseSource::kTrack : PoseSource::kGroundTruth;
}

void noteCameraGuess(const Sequence& sequence, const std::string& verb) {
  if (!sequence.cameraGuessed()) return;
  const PinholeCamera& c = sequence.camera();
  std::fprintf(stderr,
               "vdmap %s: note: %s: no camera given, guessed %s: fx %g fy %g cx %g cy %g, depth scale %g; "
               "--camera PRESET or a camera.yaml in the folder sets it\n",
               verb.c_str(), sequence.folder().string().c_str(), sequence.cameraSource().c_str(), c.fx, c.fy, c.cx,
               c.cy, c.depth_scale);
}

Sequence openSequence(const SequenceArgs& args, bool cut_range_at_end, std::optional<SequenceContinuation> continues) {
  SequenceOptions options;
  options.continues = std::move(continues);
  options.camera_preset = args.camera;
  options.cut_range_at_end = cut_range_at_end;
  // No --poses: the recorded poses when there are some (frames without a pose are then dropped,
  // as with --poses gt), else tracking.
  options.poses = args.poses == "gt"      ? SequenceOptions::Poses::kRecorded
                  : args.poses == "track" ? SequenceOptions::Poses::kOptional
                                          : SequenceOptions::Poses::kAuto;
  if (!args.frames.empty()) options.frames = parseFrameRange(args.frames);
  options.topics = args.topics;
  options.max_rgb_dt_s = args.rgb_window_s;
  return Sequence::open(args.folder, options);
}

}  // namespace vdmap::app
