#include "app/commands.h"
#include "mapping/io/camera_config.h"

namespace vdmap::app {

std::string cameraPresetList() {
  std::string presets;
  for (const std::string& n : cameraPresetNames()) presets += (presets.empty() ? "" : ", ") + n;
  return presets;
}

void addSequenceArgs(CLI::App& verb, SequenceArgs& args) {
  verb.add_option("SEQ", args.folder, "TUM RGB-D layout sequence folder")->required();
  verb.add_option("--camera", args.camera, "camera preset overriding the folder's: " + cameraPresetList());
  verb.add_option("--frames", args.frames,
                  "frames A:B of the depth list (B exclusive; A: or :B; a plain N means 0:N, the first N frames); "
                  "a range past the end is an error");
}

TumSequence openSequence(const SequenceArgs& args, bool cut_range_at_end) {
  SequenceOptions options;
  options.camera_preset = args.camera;
  options.cut_range_at_end = cut_range_at_end;
  if (!args.frames.empty()) options.frames = parseFrameRange(args.frames);
  return TumSequence::open(args.folder, options);
}

}  // namespace vdmap::app
