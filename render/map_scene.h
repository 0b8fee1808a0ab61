#pragma once
// Render inputs from mapping results: the one place where mapping's ellipsoids and keyframe
// graph become the plain render-side types of scene_types.h (shared by `vdmap render` and the
// workbench).
#include <span>
#include <vector>

#include "mapping/files/map_file.h"
#include "mapping/files/ply_reader.h"
#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/local_map/ellipsoid_filter.h"
#include "mapping/pipeline/mapper.h"
#include "render/scene_lines.h"

namespace vdmap::render {

/// Mapping ellipsoids as render instances (same frame; colour rounded and clamped to 0..255).
std::vector<EllipsoidInstance> toInstances(std::span<const Ellipsoid> ellipsoids);
/// Ellipsoids read from a map PLY (docs/method.md 11) as render instances.
std::vector<EllipsoidInstance> toInstances(std::span<const EllipsoidRecord> records);
/// A mesh read from a PLY as the mesh renderer's input.
ColoredMesh toColoredMesh(const ColoredTriangleMesh& mesh);

/// The world's up direction estimated from the data: the mean of the cameras' image-up
/// directions (-y of each camera, which a hand-held or robot camera keeps roughly level),
/// replaced by the normal of the map's largest plane within 40 degrees of it (floor, tables,
/// ceiling: level surfaces, found by RANSAC over the ellipsoid means), which removes the bias of
/// cameras that look down. Without cameras (a map PLY, an OctoMap), or with cameras that point
/// every way, the map's level planes alone (levelUp); +z when it has none either. Unit length,
/// deterministic. `from`, when given, receives which of the three gave it.
enum class UpFrom { kCameras, kLevelPlanes, kDefault };
glm::vec3 estimateUp(std::span<const Transform> T_W_C, std::span<const Ellipsoid> map, UpFrom* from = nullptr);

/// A keyframe graph and mapper state (a session's, or a Mapper's) as the 3-D view draws it, as
/// the workbench's snapshot has it: the keyframe poses, covisibility edges, loop closures, every
/// mapped frame's pose (the keyframes' for sessions that lack them) and the current keyframe.
GraphScene graphSceneOf(const KeyframeGraph& graph, const MapperState& state, const PinholeCamera& camera,
                        bool tracked);
/// A map file's keyframes, covisibility edges and trajectory as the workbench draws them: the
/// trajectory only beside keyframes (else the keyframes stand for it), the frustums in the
/// shape of kStaticMapCamera (a map folder stores no intrinsics).
GraphScene graphSceneOf(const StaticMap& map);

}  // namespace vdmap::render
