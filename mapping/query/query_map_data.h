#pragma once
// What QueryMap::build builds (internal to mapping/query).
#include "mapping/query/keyframe_views.h"
#include "mapping/query/query_map.h"
#include "mapping/query/surface_index.h"

namespace vdmap {

struct QueryMap::Data {
  QueryParams params;
  KeyframeViews views;    ///< free space, per-keyframe verdicts (keyframe_views.cpp)
  SurfaceIndex surface;   ///< occupied gates, distance, rays (surface_index.cpp)
};

}  // namespace vdmap
