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

/// How a method classified a set of points: counts and each class's share.
struct OccupancyShares {
  std::size_t points = 0, n_occupied = 0, n_free = 0, n_unknown = 0;
  void add(Occupancy s);
  double occupied() const { return share(n_occupied); }
  double free() const { return share(n_free); }
  double unknown() const { return share(n_unknown); }
  /// bench.json's {"occupied", "free", "unknown"}: the shares, rounded.
  nlohmann::json json() const;

 private:
  double share(std::size_t k) const { return points ? static_cast<double>(k) / static_cast<double>(points) : 0.0; }
};

/// The maps the causes of vdmap's misses are found with, built once for every report: `all` keeps
/// every cell of two or more points (no filter), `few` the kept cells and those of fewer points than
/// the filter's minimum, `unfused` the global map without fusion across groups, `merged` without
/// occlusion removal either (merging alone).
struct HeldOutDiagnostics {
  HeldOutDiagnostics(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& qp);
  QueryMap all, few, unfused, merged;
};

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
                             const QueryMap& query, const HeldOutDiagnostics& diagnostics,
                             const std::vector<HeldOutPeer>& peers, std::ostringstream* text);

/// For each of `points` (truth occupied) vdmap does not call occupied, the first stage of the map
/// that does not hold it. Appends the counts to `text`; returns them.
nlohmann::json reportSurfaceMisses(const std::vector<Eigen::Vector3d>& points, const char* what,
                                   const KeyframeGraph& graph, const GlobalMap& global, const QueryMap& query,
                                   const HeldOutDiagnostics& diagnostics, std::ostringstream* text);

}  // namespace vdmap::app
