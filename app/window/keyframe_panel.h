#pragma once
// The right panel's keyframe sections: the keyframe list, the selected keyframe's inspector and
// pose edit, the picked ellipsoid, and the corrected-trajectory file.
#include "app/window/window_state.h"

namespace vdmap::app::gui {

/// The "Keyframes" section: the list, then the selected keyframe's figures, container view,
/// neighbours and pose.
void drawKeyframes(Workbench& bench, const render::MapMirror& mirror, WindowState& win);
/// The "Picked ellipsoid" section.
void drawPicked(Workbench& bench, WindowState& win);
/// The "Pose correction" section: a corrected TUM trajectory to load.
void drawPoseFile(Workbench& bench);

}  // namespace vdmap::app::gui
