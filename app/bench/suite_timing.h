#pragma once
// vdmap bench --suite FILE: the speed of `vdmap render --suite`, stage by stage
// (docs/performance.md "Rendering").
#include <string>

namespace vdmap::app {

/// Runs a render suite `runs` times in this process, comparing with its goldens, and prints the
/// medians of each stage (validate and of it load, offscreen context, global-map builds, per
/// view render and check, total; the first run pays the context, as a `vdmap render --suite`
/// process does once) and the maps loaded and global maps built per run, or with `json` the same
/// as JSON. `file` is a suite (views.yaml: its goldens must exist; failing views' images and
/// junit.xml go to its out folder, as `vdmap render --suite` writes them), or a session (.vdmap):
/// then a suite of 20 views of it (8 global views orbiting the map, 6 keyframe views and 6
/// containers, keyframes spread over the session, default sizes) is written into a temporary
/// folder and run once with --update first (its own line), and the session's load is timed with
/// and without decoding every keyframe's images (the workbench's load and render's). Throws
/// InputError for a file that is neither, or a suite that does not validate.
void runSuiteBench(const std::string& file, int runs, bool json);

}  // namespace vdmap::app
