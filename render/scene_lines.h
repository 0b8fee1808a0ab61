#pragma once
// Line sets for the global view: keyframe frustums, covisibility edges, the trajectory.
#include <optional>
#include <span>
#include <vector>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"
#include "render/scene_types.h"

namespace vdmap::render {

/// A covisibility edge between keyframes a and b with its weight in [0, 1].
struct GraphEdge {
  int a = 0, b = 0;
  float weight = 1.f;
};

/// The keyframe graph as the 3-D view draws it (world frame).
struct GraphScene {
  PinholeCamera camera;
  std::vector<Transform> keyframes;    ///< T_W_K by keyframe id
  std::vector<GraphEdge> edges;        ///< covisibility edges, viridis by weight
  std::vector<GraphEdge> loops;        ///< loop-closure edges (kLoopEdgeColor), drawn with the graph
  std::vector<Transform> trajectory;   ///< T_W_C per mapped frame; the last one is the current camera
  std::vector<Transform> groundtruth;  ///< T_W_C of the sequence's ground truth (kGroundTruthColor), if shown
  int current_keyframe = -1;           ///< drawn yellow
  int selected_keyframe = -1;          ///< drawn white
  bool tracked = false;                ///< tracked poses (PoseSource::kTrack): the legend keys the lines
};

/// Line colours the window's legend names: the (estimated) trajectory, the ground-truth
/// trajectory beside it, loop-closure edges (apart from viridis, keyframe yellow and camera red).
constexpr glm::u8vec3 kTrajectoryColor{90, 200, 255}, kGroundTruthColor{120, 235, 120}, kLoopEdgeColor{255, 120, 20};

/// Depth of the drawn frustums, m: keyframes and the camera now (the view frames them whole).
constexpr float kKeyframeFrustumDepthM = 0.25f, kCameraFrustumDepthM = 0.15f;

/// Adds the frustum of a camera at T_W_K: the image corners at `depth_m`, joined to the centre.
void addFrustum(ColoredLines& lines, const PinholeCamera& camera, const Transform& T_W_K, float depth_m,
                const glm::u8vec3& color);
/// Adds one segment per edge between the keyframe centres, coloured by weight on the viridis
/// ramp (weak edges dark, strong ones bright) or all in `color`. Edges naming unknown keyframes
/// are skipped.
void addEdges(ColoredLines& lines, std::span<const Transform> T_W_K, std::span<const GraphEdge> edges,
              const std::optional<glm::u8vec3>& color = std::nullopt);
/// Adds the polyline through the camera centres.
void addTrajectory(ColoredLines& lines, std::span<const Transform> T_W_C, const glm::u8vec3& color);

}  // namespace vdmap::render
