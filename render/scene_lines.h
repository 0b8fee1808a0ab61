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

/// Adds the frustum of a camera at T_W_K: the image corners at `depth_m`, joined to the centre.
void addFrustum(ColoredLines& lines, const PinholeCamera& camera, const Transform& T_W_K,
                float depth_m, const glm::u8vec3& color);
/// Adds one segment per edge between the keyframe centres, coloured by weight on the viridis
/// ramp (weak edges dark, strong ones bright) or all in `color`. Edges naming unknown keyframes
/// are skipped.
void addEdges(ColoredLines& lines, std::span<const Transform> T_W_K, std::span<const GraphEdge> edges,
              const std::optional<glm::u8vec3>& color = std::nullopt);
/// Adds the polyline through the camera centres.
void addTrajectory(ColoredLines& lines, std::span<const Transform> T_W_C, const glm::u8vec3& color);

}  // namespace vdmap::render
