#pragma once
// What QueryMap::build builds.
#include "mapping/query/detail/keyframe_views.h"
#include "mapping/query/detail/surface_index.h"
#include "mapping/query/query_map.h"

namespace vdmap {

struct QueryMap::Data {
  QueryParams params;
  KeyframeViews views;   ///< free space, per-keyframe verdicts (keyframe_views.cpp)
  SurfaceIndex surface;  ///< occupied gates, distance, rays (surface_index.cpp)
};

}  // namespace vdmap
