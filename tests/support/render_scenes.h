#pragma once
// Small fixed scenes for the renderer's tests (golden images and projection checks).
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

#include "mapping/core/camera.h"
#include "mapping/local_map/ellipsoid_filter.h"
#include "render/scene_lines.h"
#include "render/scene_types.h"

namespace vdmap::test {

/// 20 ellipsoids on a 5x4 grid in the plane z = 0 (x in [-1, 1], y in [-0.75, 0.75]) with
/// varying orientation, size, colour, keyframe and count.
std::vector<render::EllipsoidInstance> gridEllipsoids();
/// The same grid as mapping ellipsoids (what the workbench's snapshots and a session hold).
std::vector<Ellipsoid> gridMap();

/// A 160x120 camera (fx = fy = 150) for container views.
PinholeCamera smallCamera();
/// A 160x120 RGB test card: colour ramps with a checkerboard.
cv::Mat testCard();

/// A covariance with principal standard deviations (sx, sy, sz) rotated by `yaw` about z.
glm::mat3 covariance(float sx, float sy, float sz, float yaw);

/// A coloured unit cube standing on a 3 x 3 m floor (vertex colours, flat faces).
render::ColoredMesh cubeOnFloor();

/// Six keyframes on a circle of radius 1.5 m at height 1 m looking at the origin.
std::vector<Transform> ringOfKeyframes(int n = 6);

/// The built-in scene's walk of `frames` poses a lap as a sequence folder (render::
/// writeBuiltinSequence), rendered once for every test process of this build of vdmap: each test
/// runs in a process of its own, and rendering the frames (the sensor noise above all) cost
/// every one of them seconds. Read only: copy it to change it.
std::filesystem::path builtinSequence(int frames);

}  // namespace vdmap::test
