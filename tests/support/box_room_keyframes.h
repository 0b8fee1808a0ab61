#pragma once
// Keyframes of the analytic box room (tests/support/test_util.h) for global-map and export tests.
#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/local_map/local_map_integrator.h"
#include "tests/support/test_util.h"

namespace vdmap::test {

/// Adds a keyframe at `T_W_K` whose local map holds one ray-cast frame of the box room from that
/// pose, and whose map is then placed at `T_W_placed` (a pose error, to shift surfaces).
/// Returns its id.
inline int addBoxRoomKeyframe(KeyframeGraph* graph, const PinholeCamera& camera, const Transform& T_W_K,
                              const Transform& T_W_placed, int cell_size_px = 5) {
  Keyframe k{0, 0, 0.0, T_W_K, {}, {}, {}, KeyframeContainer(camera, cell_size_px), 0, {}};
  k.timestamp = static_cast<double>(graph->size());
  LocalMapIntegrator integrator;
  integrator.integrateFrame(renderBoxRoom(camera, T_W_K), camera, T_W_K, &k.container, nullptr);
  k.T_W_K = T_W_placed;
  return graph->add(std::move(k)).id;
}

/// Two neighbouring keyframes looking at the same wall of the box room (tum-default camera),
/// joined by an edge of weight 0.6: the smallest graph with a merge group.
inline void addTwoBoxRoomViews(KeyframeGraph* graph, const PinholeCamera& camera) {
  addBoxRoomKeyframe(graph, camera, lookAt({0, 0, 0}, {0, 0, 2}), lookAt({0, 0, 0}, {0, 0, 2}));
  const Transform T = lookAt({0.3, 0, 0.2}, {0.5, 0.2, 2});
  addBoxRoomKeyframe(graph, camera, T, T);
  graph->edges().strengthen(0, 1, 0.6);
}

}  // namespace vdmap::test
