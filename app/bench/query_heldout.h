#pragma once
// vdmap bench SEQ --query: the held-out check on the mapped frames' own depth (docs/results.md
// "Queries"). Per frame, seeded pixels away from depth edges give four points on the pixel's
// ray: the measured surface point (what the frame measured is occupied), 2 and 5 cm in front of
// it and half way to the camera (free). Every method classifies them; for vdmap's surface points
// not called occupied, the report says why (which stage of the map does not hold them).
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"
#include "mapping/query/query_map.h"

namespace vdmap::app {

struct HeldOutPoints {
  std::vector<Eigen::Vector3d> surface, front_2cm, front_5cm, half_way;
};

/// Adds `per_frame` seeded pixels of one frame (depth in [min_m, max_m], the 3x3 depths around
/// within 5 cm of the pixel's) to `out`.
void addHeldOut(const RgbdFrame& frame, const PinholeCamera& camera, double min_m, double max_m,
                std::size_t frame_index, std::size_t per_frame, HeldOutPoints* out);

struct HeldOutPeer {
  std::string name, key;
  std::function<Occupancy(const Eigen::Vector3d&)> classify;
};

/// Classifies the points with vdmap's query map and each peer; for vdmap's surface points not
/// called occupied, their cause. Appends the table to `text`; returns bench.json's figures.
nlohmann::json reportHeldOut(const HeldOutPoints& points, const KeyframeGraph& graph, const GlobalMap& global,
                             const QueryMap& query, const std::vector<HeldOutPeer>& peers, std::ostringstream* text);

/// For each of `points` (truth occupied) vdmap does not call occupied, the first stage of the map
/// that does not hold it. Appends the counts to `text`; returns them.
nlohmann::json reportSurfaceMisses(const std::vector<Eigen::Vector3d>& points, const char* what,
                                   const KeyframeGraph& graph, const GlobalMap& global, const QueryMap& query,
                                   std::ostringstream* text);

}  // namespace vdmap::app
