#pragma once
// vdmap bench SEQ --query: vdmap's point queries in detail, beyond the comparison with OctoMap
// (docs/performance.md "Queries"): each conflict rule, the distance near surfaces and in open
// space, ray casting, and the query map's memory by part.
#include <span>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "mapping/query/query_map.h"

namespace vdmap::app {

/// What the comparison already built and timed, borrowed.
struct QueryDetailInput {
  const KeyframeGraph& graph;
  const GlobalMap& global;
  const QueryMap& query;                       ///< built from graph and global, ConflictRule::kOccupied, one thread
  int passes;                                  ///< every figure is the median of this many passes
  std::span<const Eigen::Vector3d> points;     ///< even indices uniform in the seen box, odd near surfaces
  std::span<const Classification> classified;  ///< query.classify(points)
  double classify_ms;                          ///< its median time
  std::span<const Eigen::Vector3d> distance_points;  ///< a prefix of `points`
  const PinholeCamera& camera;
  std::span<const Transform> views;  ///< castView poses (the first one's pixel rays are cast as rays)
  double max_range_m;                ///< of the views and rays
};

/// One thread, process CPU time, medians of in.passes: classify of in.points under each conflict
/// rule (kOccupied's from the comparison, kRecent's and kPrecise's on maps built with them) with
/// the share of each class; distance on the near and the uniform half of in.distance_points apart;
/// castRays on the first view's pixel rays, and whether castView gives bit for bit the same
/// answers; the query map's heap bytes, total and by part. Appends the lines to `text` and
/// returns the figures (bench.json's `query.vdmap`).
nlohmann::json timeQueryDetail(const QueryDetailInput& in, std::ostringstream* text);

}  // namespace vdmap::app
