#include "mapping/global_map/global_map.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>

#include <tbb/enumerable_thread_specific.h>

#include "mapping/core/parallel.h"
#include "mapping/core/timing.h"
#include "mapping/global_map/fusion_across_groups.h"
#include "mapping/global_map/merge_within_groups.h"
#include "mapping/global_map/occlusion_removal.h"

// The build (docs/method.md 6.4): merge groups (6.1, merge_groups.cpp), merging within each group
// (6.2, merge_within_groups.cpp), occlusion removal (6.3, occlusion_removal.cpp) and fusion across
// groups (7, fusion_across_groups.cpp), each stage timed for the reported figures.
namespace vdmap {
namespace global_map_detail {

// What a build keeps in a GlobalMapWorkspace (names as in buildGlobalMap's steps).
struct WorkspaceBuffers {
  // False for a build's own buffers (no workspace given): each step then frees what the later
  // ones no longer read and keeps only its output, so a one-off build (vdmap map) peaks lower.
  bool keep = true;
  // Per keyframe id: its kept cells and what they were computed from.
  struct Kept {
    std::uint64_t container = 0, revision = 0;
    FilterParams filter;
    std::vector<bool> kept;
  };
  std::vector<Kept> kept;
  std::vector<std::vector<Ellipsoid>> merged;  // per merge group
  tbb::enumerable_thread_specific<MergeScratch> merge_scratch;
  // Ellipsoid i of the merge is *merged_at[i], from group group_of[i]: merged[g] holds
  // ellipsoids offset[g] .. offset[g + 1] - 1.
  std::vector<std::size_t> offset, kept_offset;
  std::vector<const Ellipsoid*> merged_at;
  std::vector<int> group_of, kept_group_of;
  std::vector<double> lambda_max, kept_lambda_max;
  std::vector<char> removed;
  std::vector<const Ellipsoid*> survivor;  // into merged: what occlusion removal kept, in order
  OcclusionBuffers occlusion;
  FusionBuffers fusion;
};

namespace {

using Clock = std::chrono::steady_clock;

// Occlusion removal and fusion both rank the ellipsoids by lambda_max.
bool needsLambdaMax(const GlobalMapParams& params) { return params.occlusion_removal || params.fuse_across_groups; }

// map->kept and map->sigma_e. The filter's answer depends on a container and the filter
// parameters only, not on poses: a rebuild after a loop closure reuses it for every keyframe.
void filterLocalMaps(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws, GlobalMap* map) {
  ws->kept.resize(graph.size());
  parallelFor(params.threads, graph.size(), [&](std::size_t k) {
    const KeyframeContainer& box = graph.keyframe(static_cast<int>(k)).container;
    WorkspaceBuffers::Kept& cached = ws->kept[k];
    // (id, revision) name the container's cells exactly (keyframe_container.h); ids start at 1, so
    // a new entry (container 0) never matches.
    if (cached.container != box.id() || cached.revision != box.revision() || cached.filter != params.filter)
      cached = {box.id(), box.revision(), params.filter, keptCells(box, params.filter)};
  });
  map->kept.resize(graph.size());
  for (std::size_t k = 0; k < graph.size(); ++k) {
    map->kept[k] = ws->kept[k].kept;
    map->sigma_e += static_cast<std::size_t>(std::count(map->kept[k].begin(), map->kept[k].end(), true));
  }
}

// Every group of map->groups merged (ws->merged), then indexed as one list: offset, merged_at,
// group_of and, when a later stage needs it, lambda_max. Sets map->merged.
void mergeWithinGroups(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws,
                       GlobalMap* map) {
  ws->merged.resize(map->groups.size());
  parallelFor(params.threads, map->groups.size(), [&](std::size_t g) {
    mergeGroup(graph, map->groups[g], params, map->kept, &ws->merge_scratch.local(), &ws->merged[g]);
    if (!ws->keep) ws->merged[g].shrink_to_fit();  // reserved for all of the group's inputs
  });
  if (!ws->keep) ws->merge_scratch.clear();
  const std::size_t groups = ws->merged.size();
  ws->offset.assign(groups + 1, 0);
  for (std::size_t g = 0; g < groups; ++g) ws->offset[g + 1] = ws->offset[g] + ws->merged[g].size();
  const std::size_t n = ws->offset.back();
  map->merged = n;
  const bool need_lambda = needsLambdaMax(params);
  ws->merged_at.resize(n);
  ws->group_of.resize(n);
  ws->lambda_max.resize(need_lambda ? n : 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    for (std::size_t l = 0; l < ws->merged[g].size(); ++l) {
      ws->merged_at[ws->offset[g] + l] = &ws->merged[g][l];
      ws->group_of[ws->offset[g] + l] = static_cast<int>(g);
      if (need_lambda) ws->lambda_max[ws->offset[g] + l] = largestEigenvalue(floored(ws->merged[g][l].cov));
    }
  });
}

// Occlusion removal over the merged ellipsoids (or none), then the survivors in order: survivor,
// kept_group_of and kept_lambda_max. Without ws->keep the survivors move to the front of their
// group's vector, which then lets the removed go.
void removeOccluded(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws) {
  const std::size_t n = ws->merged_at.size(), groups = ws->merged.size();
  if (params.occlusion_removal)
    occludingEllipsoids(graph, ws->merged_at, ws->lambda_max, params, &ws->occlusion, &ws->removed);
  else
    ws->removed.assign(n, 0);
  if (!ws->keep) releaseOcclusionBuffers(&ws->occlusion);
  ws->kept_offset.assign(groups + 1, 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    ws->kept_offset[g + 1] = static_cast<std::size_t>(
        std::count(ws->removed.begin() + static_cast<std::ptrdiff_t>(ws->offset[g]),
                   ws->removed.begin() + static_cast<std::ptrdiff_t>(ws->offset[g + 1]), 0));
  });
  std::partial_sum(ws->kept_offset.begin(), ws->kept_offset.end(), ws->kept_offset.begin());
  const std::size_t kept = ws->kept_offset.back();
  const bool need_lambda = needsLambdaMax(params);
  ws->survivor.resize(kept);
  ws->kept_group_of.resize(kept);
  ws->kept_lambda_max.resize(need_lambda ? kept : 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    std::size_t to = ws->kept_offset[g];
    std::vector<Ellipsoid>& merged = ws->merged[g];
    for (std::size_t i = ws->offset[g]; i < ws->offset[g + 1]; ++i) {
      if (ws->removed[i]) continue;
      if (ws->keep)
        ws->survivor[to] = ws->merged_at[i];
      else
        merged[to - ws->kept_offset[g]] = merged[i - ws->offset[g]];  // forward: never overwrites one still to move
      ws->kept_group_of[to] = static_cast<int>(g);
      if (need_lambda) ws->kept_lambda_max[to] = ws->lambda_max[i];
      ++to;
    }
    if (ws->keep) return;
    merged.resize(to - ws->kept_offset[g]);
    merged.shrink_to_fit();
    for (std::size_t l = 0; l < merged.size(); ++l) ws->survivor[ws->kept_offset[g] + l] = &merged[l];
  });
  if (ws->keep) return;
  releaseVector(&ws->merged_at);  // into the groups' vectors before they were compacted
  releaseVector(&ws->group_of);
  releaseVector(&ws->lambda_max);
  releaseVector(&ws->removed);
}

// map->ellipsoids: the survivors fused across groups, or as they are.
void fuseSurvivors(const GlobalMapParams& params, WorkspaceBuffers* ws, GlobalMap* map) {
  const std::size_t kept = ws->survivor.size();
  if (params.fuse_across_groups) {
    map->ellipsoids = fuseAcrossGroups(ws->survivor, ws->kept_group_of, ws->kept_lambda_max, params, &ws->fusion);
    map->merged_across_groups = kept - map->ellipsoids.size();
  } else {
    map->ellipsoids.resize(kept);
    parallelFor(params.threads, kept, [&](std::size_t k) { map->ellipsoids[k] = *ws->survivor[k]; });
  }
}

}  // namespace
}  // namespace global_map_detail

std::vector<Ellipsoid> localEllipsoids(const KeyframeGraph& graph, const GlobalMap& map) {
  std::vector<Ellipsoid> local;
  local.reserve(map.sigma_e);
  forEachLocalEllipsoid(graph, map, [&local](const Ellipsoid& e) { local.push_back(e); });
  return local;
}

void forEachLocalEllipsoid(const KeyframeGraph& graph, const GlobalMap& map,
                           const std::function<void(const Ellipsoid&)>& visit) {
  for (const Keyframe& k : graph.keyframes())
    forEachKeptEllipsoid(k.container, map.kept.at(static_cast<std::size_t>(k.id)), k.T_W_K, k.id, visit);
}

struct GlobalMapWorkspace::Buffers : global_map_detail::WorkspaceBuffers {};

GlobalMapWorkspace::GlobalMapWorkspace() : buffers_(std::make_unique<Buffers>()) {}
GlobalMapWorkspace::~GlobalMapWorkspace() = default;

GlobalMap buildGlobalMap(const KeyframeGraph& graph, const GlobalMapParams& params, GlobalMapWorkspace* workspace) {
  using namespace global_map_detail;
  params.validate();
  std::unique_ptr<GlobalMapWorkspace> own;  // this build's, without one given
  if (workspace == nullptr) workspace = (own = std::make_unique<GlobalMapWorkspace>()).get();
  WorkspaceBuffers& ws = *workspace->buffers_;
  ws.keep = own == nullptr;
  ws.fusion.keep = ws.keep;
  GlobalMap map;
  const auto start = Clock::now();
  map.groups = mergeGroups(graph, params.tau_group);
  map.groups_ms = msSince(start);

  const auto merge_start = Clock::now();
  filterLocalMaps(graph, params, &ws, &map);
  mergeWithinGroups(graph, params, &ws, &map);
  map.merge_ms = msSince(merge_start);

  // Occlusion removal before fusion: it judges each viewpoint's own group's ellipsoids, and a
  // fused ellipsoid carries only its seed's keyframe, so fusing first would hide copies from the
  // viewpoints whose coarse occluders they remove.
  const auto occlusion_start = Clock::now();
  removeOccluded(graph, params, &ws);
  map.occlusion_ms = msSince(occlusion_start);

  const auto fusion_start = Clock::now();
  fuseSurvivors(params, &ws, &map);
  map.fusion_ms = msSince(fusion_start);
  map.sigma_e_prime = map.ellipsoids.size();
  map.t_g_s = secondsSince(start);
  return map;
}

}  // namespace vdmap
